// The fixture of the end-to-end server tests (test_server.cpp, test_server_blobs.cpp): a real store
// (bunny, 512^2 in 128^2 tiles, raw + mh + mmh) served by the real server on an ephemeral loopback
// port, a ShadowMap opened on a copy of it for the expected answers (one process must not open one
// LMDB directory twice), and 10,000 surface points plus two outside the map. Built once per suite.
#pragma once

#include <gtest/gtest.h>

#include "tests/server_test_support.hpp"

namespace shadowtiles::server_testing {

class BunnyServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    store_ = dir_->path() / "bunny.store";
    auto built = run_build(bunny_config(store_, {store::Method::raw, store::Method::mh, store::Method::mmh}));
    ASSERT_TRUE(built.ok()) << built.error().message;
    std::filesystem::copy(store_, dir_->path() / "reference.store", std::filesystem::copy_options::recursive);
    auto map = ShadowMap::open(dir_->path() / "reference.store");
    ASSERT_TRUE(map.ok()) << map.error().message;
    reference_ = map->release();
    LoadOptions load;
    load.up = UpAxis::y;
    auto scene = load_scene(testing::shared_scene(kBunny), load);
    ASSERT_TRUE(scene.ok());
    points_ = new std::vector<Vec3>;
    for (const Receiver& r : sample_receivers(*scene, 10000, 7)) points_->push_back(r.position);
    points_->push_back({1e6, 0, 0});  // outside the map
    points_->push_back({0, -1e6, 3});
    server_ = new RunningServer(test_config(), &store_);
  }
  static void TearDownTestSuite() {
    delete server_;
    delete reference_;
    delete points_;
    delete dir_;
  }

  static inline TempDir* dir_ = nullptr;
  static inline std::filesystem::path store_;
  static inline ShadowMap* reference_ = nullptr;
  static inline std::vector<Vec3>* points_ = nullptr;
  static inline RunningServer* server_ = nullptr;
};

}  // namespace shadowtiles::server_testing
