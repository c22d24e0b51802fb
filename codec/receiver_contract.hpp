// Receiver contracts (docs/receiver-contracts.md): which query points a store's intervals answer
// exactly. Chosen at build time (`build --receivers`), recorded in the store's meta ("receivers";
// stores without the field are `anywhere`), part of the build identity.
// - anywhere: a receiver may be anywhere in space outside closed solids (moving characters).
// - surfaces: receivers lie on the scene's surfaces (baked lightmaps, solar-access studies); any
//   value up to the second surface answers them, so open worlds compress.
#pragma once

#include <optional>
#include <string_view>

namespace shadowtiles {

enum class ReceiverContract { anywhere, surfaces };

inline const char* receiver_contract_name(ReceiverContract contract) {
  return contract == ReceiverContract::surfaces ? "surfaces" : "anywhere";
}

inline std::optional<ReceiverContract> parse_receiver_contract(std::string_view name) {
  if (name == "anywhere") return ReceiverContract::anywhere;
  if (name == "surfaces") return ReceiverContract::surfaces;
  return std::nullopt;
}

}  // namespace shadowtiles
