#include "common/parallel_for.hpp"

#include <algorithm>
#include <thread>
#include <vector>

namespace shadowtiles {

void parallel_for_ranges(unsigned threads, size_t count, const std::function<void(size_t, size_t)>& fn) {
  const size_t parts = std::max<size_t>(1, std::min<size_t>(std::max(threads, 1u), count));
  std::vector<std::thread> helpers;
  helpers.reserve(parts - 1);
  for (size_t p = 1; p < parts; ++p) helpers.emplace_back([&, p] { fn(count * p / parts, count * (p + 1) / parts); });
  fn(0, count / parts);
  for (auto& helper : helpers) helper.join();
}

}  // namespace shadowtiles
