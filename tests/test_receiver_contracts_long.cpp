// Long variant (label `long`): every shared scene at 4096^2 (terrains as heightfields, as the bench builds them), MH, MMH and DAG-MH inside their
// capped intervals under both contracts, checked by verify's brute-force reference caps.
#include <gtest/gtest.h>

#include "receiver_contracts_scenes.hpp"

namespace shadowtiles::testing {
namespace {

TEST(ReceiverContractsLong, EveryTexelInsideItsCappedIntervalAt4096) {
  const ContractScene scenes[] = {{"fzk_haus", "fzk_haus/fzk_haus.obj", "y"},
                                  {"bunny", "bunny/stanford-bunny.obj", "y"},
                                  {"honolulu", "honolulu_airport/honolulu_airport_harbour.ply", "z"},
                                  {"dragon", "dragon_res2/dragon_vrip_res2.ply", "y"},
                                  {"nefertiti", "nefertiti/nefertiti.obj", "z"},
                                  {"terragen", "terragen/RealisticTerrain.ter", "z"},
                                  {"oahu", "oahu/oahu_w158n21.ply", "z"}};
  for (const ContractScene& scene : scenes) {
    const std::string name = scene.name;
    const std::string extra = name == "terragen" || name == "oahu" ? "--heightfield '*'" : "";
    for (const char* receivers : {"anywhere", "surfaces"}) {
      TempDir dir;
      build_and_verify(scene, receivers, 4096, dir.path() / "s", extra);
    }
  }
}

}  // namespace
}  // namespace shadowtiles::testing
