// End to end for the streaming client (client/http_tile_source.hpp, client/streaming_client.hpp):
// a real store (bunny, 1024^2 in 128^2 tiles, every method the builder makes) served by the real
// server on an ephemeral loopback port. The client's answers are compared with the server's own
// /v1/shadow answers and with a ShadowMap on a copy of the store (one process must not open one
// LMDB directory twice), through a memory cache far smaller than the store. Also: offline
// behaviour once the server stops, retries against a dead port, corrupt blobs (stored corrupt, and
// flipped on the way by a loopback proxy), the disk cache with ETag revalidation, and the tile sets
// of the prefetch helpers.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <cmath>
#include <set>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "builder/build_job.hpp"
#include "builder/receiver_sampler.hpp"
#include "builder/scene_loader.hpp"
#include "client/streaming_client.hpp"
#include "server/server.hpp"
#include "store/blob.hpp"
#include "store/lmdb_store.hpp"
#include "store/tile_key.hpp"
#include "tests/running_server.hpp"
#include "tests/scene_build_config.hpp"
#include "tests/store_damage.hpp"
#include "tests/testing_support.hpp"

namespace shadowtiles {
namespace {

using nlohmann::json;
using testing::TempDir;

constexpr const char* kBunny = "bunny/stanford-bunny.obj";
constexpr size_t kPoints = 10000;

// The bunny as an open scan (--no-nearly-closed): full-depth trees, so tiles are large enough for the
// small caches below to evict.
BuildConfig bunny_config(const std::filesystem::path& out, std::vector<store::Method> methods) {
  BuildConfig config =
      testing::shared_scene_config({kBunny, UpAxis::y, false}, out, 1024, 128, std::move(methods), 135, 45);
  config.close_nearly_closed = false;
  return config;
}

void copy_store(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::filesystem::copy(from, to, std::filesystem::copy_options::recursive);
}

using testing::RunningServer;

// A loopback proxy in front of `upstream` that can damage tile blobs on the way: the first
// `flips_left` answers for tile paths containing `target` get one payload bit flipped.
class FlippingProxy {
 public:
  FlippingProxy(int upstream_port, std::string target, int flips) : target_(std::move(target)), flips_left_(flips) {
    http_.Get(R"(/.*)", [this, upstream_port](const httplib::Request& req, httplib::Response& res) {
      httplib::Client upstream("127.0.0.1", upstream_port);
      std::string path = req.path;
      if (!req.params.empty()) {
        path += '?';  // appended: GCC 12 warns falsely (-Wrestrict) on "?" + std::string
        path += httplib::detail::params_to_query_str(req.params);
      }
      auto answer = upstream.Get(path);
      if (!answer) {
        res.status = 502;
        return;
      }
      res.status = answer->status;
      std::string body = answer->body;
      if (req.path.find(target_) != std::string::npos) {
        ++target_requests_;
        if (answer->status == 200 && flips_left_.fetch_sub(1) > 0) body[body.size() - 3] ^= 0x04;
      }
      for (const char* header : {"ETag", "Cache-Control"})
        if (answer->has_header(header)) res.set_header(header, answer->get_header_value(header));
      if (answer->status != 204 && answer->status != 304)
        res.set_content(body, answer->get_header_value("Content-Type"));
    });
    port_ = http_.bind_to_any_port("127.0.0.1");
    thread_ = std::thread([this] { http_.listen_after_bind(); });
    while (!http_.is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ~FlippingProxy() {
    http_.stop();
    thread_.join();
  }
  std::string url() const { return "http://127.0.0.1:" + std::to_string(port_); }
  int target_requests() const { return target_requests_; }

 private:
  httplib::Server http_;
  std::string target_;
  std::atomic<int> flips_left_;
  std::atomic<int> target_requests_{0};
  int port_ = 0;
  std::thread thread_;
};

// A loopback port with nothing listening (bound once by the kernel's choice, then released).
int dead_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  EXPECT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  socklen_t length = sizeof address;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  ::close(fd);
  return ntohs(address.sin_port);
}

HttpTileSource::Options fast_retries() {
  HttpTileSource::Options options;
  options.max_attempts = 3;
  options.initial_backoff = std::chrono::milliseconds(1);
  options.max_backoff = std::chrono::milliseconds(4);
  options.connect_timeout = std::chrono::milliseconds(500);
  return options;
}

// One build shared by all tests: built once, served from `served`, read locally from `local`.
class StreamingClientTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    const auto built_store = dir_->path() / "bunny.store";
    auto built = run_build(bunny_config(built_store, {store::Method::raw, store::Method::mh, store::Method::mmh,
                                                      store::Method::dagmh}));
    ASSERT_TRUE(built.ok()) << built.error().message;
    copy_store(built_store, dir_->path() / "local.store");
    LoadOptions load;
    load.up = UpAxis::y;
    auto scene = load_scene(testing::shared_scene(kBunny), load);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    points_ = new std::vector<Vec3>();
    for (const Receiver& r : sample_receivers(*scene, kPoints, 9)) points_->push_back(r.position);
    // In tile order, as a renderer's coherent lookups; the halves reach different tiles.
    auto map = ShadowMap::open(dir_->path() / "local.store");
    ASSERT_TRUE(map.ok());
    auto order = [&](const Vec3& p) {
      TileCoord tile = *(*map)->tile_of(p);
      return std::pair{TileLayout::morton_index(tile), p};
    };
    std::sort(points_->begin(), points_->end(), [&](const Vec3& a, const Vec3& b) { return order(a) < order(b); });
  }
  static void TearDownTestSuite() {
    delete points_;
    delete dir_;
  }
  static std::filesystem::path served_store() { return dir_->path() / "bunny.store"; }
  static std::filesystem::path local_store() { return dir_->path() / "local.store"; }

  static TempDir* dir_;
  static std::vector<Vec3>* points_;
};
TempDir* StreamingClientTest::dir_ = nullptr;
std::vector<Vec3>* StreamingClientTest::points_ = nullptr;

// The stored values `map` answers for `points` (every query must answer).
void query_values(const ShadowMap& map, store::Method method, std::span<const Vec3> points, std::vector<float>& values) {
  values.clear();
  for (const Vec3& p : points) {
    auto answer = map.query(p, method);
    ASSERT_TRUE(answer.ok()) << answer.error().message;
    values.push_back(answer->value);
  }
}

// The server's batch answers (JSON: doubles survive exactly) for `points`.
std::vector<double> server_answers(const std::string& url, const std::vector<Vec3>& points, store::Method method,
                                   unsigned pcf) {
  httplib::Client client(url);
  client.set_read_timeout(60, 0);
  json body = {{"points", json::array()}, {"method", store::method_name(method)}};
  for (const Vec3& p : points) body["points"].push_back({p[0], p[1], p[2]});
  if (pcf > 0) body["pcf"] = pcf;
  auto response = client.Post("/v1/shadow", body.dump(), "application/json");
  EXPECT_TRUE(response);
  if (!response) return {};
  EXPECT_EQ(response->status, 200) << response->body;
  return json::parse(response->body)["lit"].get<std::vector<double>>();
}

TEST_F(StreamingClientTest, AnswersLikeTheServerAndTheLocalStoreThroughASmallCache) {
  RunningServer running(served_store());
  auto local = open_shadow_map(local_store().string(), {});
  ASSERT_TRUE(local.ok()) << local.error().message;
  ASSERT_GE((*local)->meta().methods.size(), 4u);
  for (store::Method method : (*local)->meta().methods) {
    SCOPED_TRACE(store::method_name(method));
    // A cache holding a few decoded tiles while the points touch dozens: tiles are evicted and
    // fetched again, and the answers must not change.
    StreamingOptions options;
    options.map.cache_bytes = 96 << 10;
    auto remote = open_shadow_map(running.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    const HttpTileSource* http = http_source(**remote);
    ASSERT_NE(http, nullptr);
    EXPECT_EQ(http->build_id(), (*local)->meta().config_hash);
    EXPECT_TRUE(http->uses_build_routes()) << "the server has /v1/builds/{id}/...";

    const std::vector<double> server_point = server_answers(running.url(), *points_, method, 0);
    const std::vector<double> server_pcf = server_answers(running.url(), *points_, method, 3);
    ASSERT_EQ(server_point.size(), kPoints);
    ASSERT_EQ(server_pcf.size(), kPoints);

    // Two decoding threads share the client, as a renderer's workers would, walking the points
    // tile by tile (coherent, so the small cache still hits; each tile is loaded again later).
    std::atomic<size_t> mismatches{0}, errors{0}, lit_count{0};
    std::string first_error;
    std::mutex error_mutex;
    auto work = [&](size_t begin, size_t step) {
      for (size_t i = begin; i < kPoints; i += step) {
        const Vec3& p = (*points_)[i];
        auto remote_point = (*remote)->query(p, method);
        auto local_point = (*local)->query(p, method);
        auto remote_pcf = (*remote)->query_pcf(p, method, 3);
        auto local_pcf = (*local)->query_pcf(p, method, 3);
        if (!remote_point || !local_point || !remote_pcf || !local_pcf) {
          std::lock_guard lock(error_mutex);
          if (first_error.empty())
            first_error = !remote_point ? remote_point.error().message : !remote_pcf ? remote_pcf.error().message : "local";
          ++errors;
          continue;
        }
        lit_count += remote_point->lit;
        bool same = remote_point->lit == local_point->lit && remote_point->value == local_point->value &&
                    (remote_point->lit ? 1.0 : 0.0) == server_point[i] && *remote_pcf == *local_pcf &&
                    float(*remote_pcf) == float(server_pcf[i]);
        if (!same) ++mismatches;
      }
    };
    std::thread second(work, 1, 2);
    work(0, 2);
    second.join();
    EXPECT_EQ(errors.load(), 0u) << first_error;
    EXPECT_EQ(mismatches.load(), 0u);
    // Both answers occur, so agreement is not trivial.
    EXPECT_GT(lit_count.load(), kPoints / 20);
    EXPECT_LT(lit_count.load(), kPoints - kPoints / 20);

    const CacheStats cache = (*remote)->cache_stats();
    EXPECT_LE(cache.bytes, options.map.cache_bytes + (64 << 10)) << "one tile may exceed the budget alone";
    EXPECT_GT(cache.misses, cache.tiles) << "tiles were evicted and fetched again";
    const HttpFetchStats fetched = http->stats();
    EXPECT_EQ(fetched.tiles_fetched, cache.misses) << "every miss is one tile fetch";
    EXPECT_GT(fetched.bytes_received, 0u);
    EXPECT_EQ(fetched.corrupt_refetches, 0u);
  }
}

TEST_F(StreamingClientTest, CachedTilesAnswerAfterTheServerStopsAndOthersFailClearly) {
  RunningServer running(served_store());
  StreamingOptions options;
  options.http = fast_retries();
  auto remote = open_shadow_map(running.url(), options);
  ASSERT_TRUE(remote.ok()) << remote.error().message;
  const store::Method method = (*remote)->default_method();
  // Half the points' tiles are loaded while the server runs.
  std::set<TileCoord> cached;
  std::vector<ShadowAnswer> before;
  for (size_t i = 0; i < kPoints / 2; ++i) {
    auto tile = (*remote)->tile_of((*points_)[i]);
    ASSERT_TRUE(tile.has_value());
    cached.insert(*tile);
    auto answer = (*remote)->query((*points_)[i], method);
    ASSERT_TRUE(answer.ok()) << answer.error().message;
    before.push_back(*answer);
  }
  running.stop();
  for (size_t i = 0; i < before.size(); ++i) {
    auto answer = (*remote)->query((*points_)[i], method);
    ASSERT_TRUE(answer.ok()) << "cached tile, server gone: " << answer.error().message;
    EXPECT_EQ(answer->lit, before[i].lit);
    EXPECT_EQ(answer->value, before[i].value);
  }
  // A point in a tile never fetched: an error naming the URL and the cause, after the retries.
  const Vec3* uncached = nullptr;
  for (size_t i = kPoints / 2; i < kPoints && !uncached; ++i)
    if (!cached.count(*(*remote)->tile_of((*points_)[i]))) uncached = &(*points_)[i];
  ASSERT_NE(uncached, nullptr) << "the second half of the points reaches tiles the first does not";
  const uint64_t retries_before = http_source(**remote)->stats().retries;
  auto failed = (*remote)->query(*uncached, method);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::io_error);
  EXPECT_NE(failed.error().message.find(running.url() + "/v1/"), std::string::npos) << failed.error().message;
  EXPECT_NE(failed.error().message.find("3 attempt"), std::string::npos) << failed.error().message;
  EXPECT_EQ(http_source(**remote)->stats().retries - retries_before, 2u);
}

TEST_F(StreamingClientTest, NothingListeningIsAnIoErrorAfterTheConfiguredAttempts) {
  const std::string url = "http://127.0.0.1:" + std::to_string(dead_port());
  StreamingOptions options;
  options.http = fast_retries();
  options.http.max_attempts = 4;
  auto opened = open_shadow_map(url, options);
  ASSERT_FALSE(opened.ok());
  EXPECT_EQ(opened.error().code, ErrorCode::io_error);
  EXPECT_NE(opened.error().message.find(url + "/v1/build"), std::string::npos) << opened.error().message;
  EXPECT_NE(opened.error().message.find("after 4 attempt"), std::string::npos) << opened.error().message;
  EXPECT_NE(opened.error().message.find("Connection"), std::string::npos) << "names the cause: "
                                                                          << opened.error().message;
}

TEST_F(StreamingClientTest, BadUrlsAndOptionsAreInvalidInput) {
  for (const std::string url : {"ftp://127.0.0.1:1", "http://", "http://127.0.0.1:1/x?y=1"}) {
    auto opened = HttpTileSource::open(url, {});
    ASSERT_FALSE(opened.ok()) << url;
    EXPECT_EQ(opened.error().code, ErrorCode::invalid_input) << url;
  }
  HttpTileSource::Options none;
  none.max_attempts = 0;
  auto opened = HttpTileSource::open("http://127.0.0.1:1", none);
  ASSERT_FALSE(opened.ok());
  EXPECT_EQ(opened.error().code, ErrorCode::invalid_input);
  auto missing = open_shadow_map((dir_->path() / "no-such.store").string(), {});
  EXPECT_FALSE(missing.ok());
}

// Tile (1, 1) of every method... of the raw method only: its stored blob fails its checksum.
class DamagedStoreTest : public StreamingClientTest {};

TEST_F(DamagedStoreTest, ACorruptStoredBlobIsReportedNeverDecoded) {
  TempDir dir;
  const auto damaged = dir.path() / "damaged.store";
  copy_store(served_store(), damaged);
  auto meta_map = ShadowMap::open(local_store());
  ASSERT_TRUE(meta_map.ok());
  const uint8_t level = (*meta_map)->layout().tile_level();
  // A tile that holds geometry: the one under the first point.
  const TileCoord target = *(*meta_map)->tile_of((*points_)[0]);
  meta_map->reset();
  testing::flip_a_bit_in_stored_tile(damaged, {store::Method::raw, level, target.x, target.y});
  RunningServer running(damaged);
  StreamingOptions options;
  options.http = fast_retries();
  auto remote = open_shadow_map(running.url(), options);
  ASSERT_TRUE(remote.ok()) << remote.error().message;
  auto answer = (*remote)->query((*points_)[0], store::Method::raw);
  ASSERT_FALSE(answer.ok());
  EXPECT_EQ(answer.error().code, ErrorCode::corrupt_data) << answer.error().message;
  EXPECT_EQ((*remote)->cache_stats().tiles, 0u) << "nothing was decoded or cached";
  // Other tiles and other methods of the same store still answer.
  auto other_method = (*remote)->query((*points_)[0], store::Method::mh);
  EXPECT_TRUE(other_method.ok());
}

TEST_F(StreamingClientTest, ABlobDamagedOnTheWayIsFetchedAgainThenReported) {
  RunningServer running(served_store());
  auto local = ShadowMap::open(local_store());
  ASSERT_TRUE(local.ok());
  const Vec3& point = (*points_)[0];
  const TileCoord tile = *(*local)->tile_of(point);
  const std::string tile_path = "/mh/" + std::to_string((*local)->layout().tile_level()) + "/" +
                                std::to_string(tile.x) + "/" + std::to_string(tile.y);
  auto expected = (*local)->query(point, store::Method::mh);
  ASSERT_TRUE(expected.ok());
  StreamingOptions options;
  options.http = fast_retries();
  {
    // One damaged answer: the refetch is clean and the answer right.
    FlippingProxy proxy(running.port(), tile_path, 1);
    auto remote = open_shadow_map(proxy.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    auto answer = (*remote)->query(point, store::Method::mh);
    ASSERT_TRUE(answer.ok()) << answer.error().message;
    EXPECT_EQ(answer->value, expected->value);
    EXPECT_EQ(answer->lit, expected->lit);
    EXPECT_EQ(http_source(**remote)->stats().corrupt_refetches, 1u);
    EXPECT_EQ(proxy.target_requests(), 2);
  }
  {
    // Damaged every time: corrupt_data after exactly one refetch, and nothing decoded.
    FlippingProxy proxy(running.port(), tile_path, 1000);
    auto remote = open_shadow_map(proxy.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    auto answer = (*remote)->query(point, store::Method::mh);
    ASSERT_FALSE(answer.ok());
    EXPECT_EQ(answer.error().code, ErrorCode::corrupt_data);
    EXPECT_NE(answer.error().message.find(tile_path), std::string::npos) << answer.error().message;
    EXPECT_EQ(proxy.target_requests(), 2);
    EXPECT_EQ((*remote)->cache_stats().tiles, 0u);
  }
}

TEST_F(StreamingClientTest, DiskCacheRevalidatesWithETagsAndServesOffline) {
  TempDir cache_dir;
  RunningServer running(served_store());
  StreamingOptions options;
  options.http = fast_retries();
  options.http.disk_cache_dir = cache_dir.path();
  const store::Method method = store::Method::mh;
  const std::span<const Vec3> points = std::span<const Vec3>(*points_).first(2000);
  std::vector<float> first, again;
  uint64_t first_fetched = 0;
  {
    auto remote = open_shadow_map(running.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    ASSERT_NO_FATAL_FAILURE(query_values(**remote, method, points, first));
    first_fetched = http_source(**remote)->stats().tiles_fetched;
    EXPECT_GT(http_source(**remote)->stats().bytes_received, 0u);
  }
  ASSERT_GT(first_fetched, 1u);
  {
    // A second run revalidates: 304s, no tile bytes moved, same answers.
    auto remote = open_shadow_map(running.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    ASSERT_NO_FATAL_FAILURE(query_values(**remote, method, points, again));
    EXPECT_EQ(again, first);
    const HttpFetchStats stats = http_source(**remote)->stats();
    EXPECT_GT(stats.not_modified, 0u);
    EXPECT_EQ(stats.tiles_fetched, 0u);
    EXPECT_EQ((*remote)->cache_stats().misses, first_fetched) << "the same tiles";
    // Every tile and top tree came from disk after a 304 (the points lie on geometry: no empty tiles).
    EXPECT_EQ(stats.disk_hits, stats.not_modified);
    EXPECT_GT(stats.not_modified, first_fetched);
  }
  // A damaged cache file is dropped and fetched again.
  size_t damaged = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(cache_dir.path()))
    if (entry.path().extension() == ".blob" && damaged == 0) {
      std::fstream file(entry.path(), std::ios::in | std::ios::out | std::ios::binary);
      file.seekp(40);
      file.put('\x5a');
      ++damaged;
    }
  ASSERT_EQ(damaged, 1u);
  {
    auto remote = open_shadow_map(running.url(), options);
    ASSERT_TRUE(remote.ok()) << remote.error().message;
    ASSERT_NO_FATAL_FAILURE(query_values(**remote, method, points, again));
    EXPECT_EQ(again, first);
    EXPECT_LE(http_source(**remote)->stats().tiles_fetched, 1u);
    EXPECT_EQ(http_source(**remote)->stats().corrupt_refetches, 0u);
  }
  // Offline with revalidation off: answers from disk alone.
  options.http.revalidate = false;
  auto offline_source = open_shadow_map(running.url(), options);
  ASSERT_TRUE(offline_source.ok());
  running.stop();
  ASSERT_NO_FATAL_FAILURE(query_values(**offline_source, method, points, again));
  EXPECT_EQ(again, first);
}

TEST_F(StreamingClientTest, DiskCacheStaysWithinItsBudget) {
  TempDir cache_dir;
  RunningServer running(served_store());
  StreamingOptions options;
  options.http.disk_cache_dir = cache_dir.path();
  options.http.disk_cache_bytes = 20 << 10;
  auto remote = open_shadow_map(running.url(), options);
  ASSERT_TRUE(remote.ok()) << remote.error().message;
  for (size_t i = 0; i < 3000; ++i) ASSERT_TRUE((*remote)->query((*points_)[i], store::Method::raw).ok());
  ASSERT_GT(http_source(**remote)->stats().bytes_received, uint64_t(options.http.disk_cache_bytes));
  uint64_t on_disk = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(cache_dir.path()))
    if (entry.is_regular_file()) on_disk += entry.file_size();
  EXPECT_LE(on_disk, options.http.disk_cache_bytes);
}

TEST_F(StreamingClientTest, PrefetchLoadsTheTilesAroundAPointAndUnderTheCamera) {
  auto map = ShadowMap::open(local_store());
  ASSERT_TRUE(map.ok());
  const TileLayout& layout = (*map)->layout();
  const Vec3& point = (*points_)[0];
  const TileCoord centre = *(*map)->tile_of(point);
  auto near = tiles_around(**map, point, 0);
  ASSERT_EQ(near.size(), 1u);
  EXPECT_EQ(near[0], centre);
  auto wide = tiles_around(**map, point, layout.tile_size());
  EXPECT_GE(wide.size(), 4u);
  EXPECT_LE(wide.size(), 9u);
  EXPECT_TRUE(std::find(wide.begin(), wide.end(), centre) != wide.end());
  auto everything = tiles_around(**map, point, layout.resolution());
  EXPECT_EQ(everything.size(), layout.tile_count());
  ASSERT_TRUE(prefetch_around(**map, store::Method::mh, point, layout.tile_size()).ok());
  EXPECT_EQ((*map)->cache_stats().misses, wide.size());

  // Every receiver the camera sees lies in a tile the frustum keeps; a camera facing away keeps fewer.
  const StoreMeta& meta = (*map)->meta();
  CameraView camera = default_camera(meta.scene_bounds, UpAxis::y, 320, 180);
  camera.vertical_fov_deg = 20;  // narrow, so the frustum drops tiles
  auto seen = tiles_under_frustum(**map, camera);
  std::set<TileCoord> seen_set(seen.begin(), seen.end());
  auto basis = CameraBasis::of(camera);
  ASSERT_TRUE(basis.ok());
  size_t visible = 0;
  for (const Vec3& p : *points_) {
    Vec3 d{p[0] - camera.eye[0], p[1] - camera.eye[1], p[2] - camera.eye[2]};
    double z = d[0] * basis->forward[0] + d[1] * basis->forward[1] + d[2] * basis->forward[2];
    double x = d[0] * basis->right[0] + d[1] * basis->right[1] + d[2] * basis->right[2];
    double y = d[0] * basis->up[0] + d[1] * basis->up[1] + d[2] * basis->up[2];
    if (z <= 0 || std::abs(x) > z * basis->tan_half_fov * basis->aspect || std::abs(y) > z * basis->tan_half_fov)
      continue;
    ++visible;
    EXPECT_TRUE(seen_set.count(*(*map)->tile_of(p))) << "a point in view lies in a dropped tile";
  }
  EXPECT_GT(visible, 100u);
  EXPECT_LT(seen.size(), layout.tile_count()) << "a narrow view does not need every tile";
  CameraView away = camera;
  for (int i = 0; i < 3; ++i) away.target[i] = 2 * camera.eye[i] - camera.target[i];
  EXPECT_LT(tiles_under_frustum(**map, away).size(), seen.size() / 2 + 1);
}

}  // namespace
}  // namespace shadowtiles
