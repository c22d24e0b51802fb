// The project builds with -ffp-contract=off (CMakeLists.txt): code compiled for an ISA with FMA (the
// x86-64-v3 clones, or a whole build for such a -march) rounds `a * b + c` twice, as written, so a
// store's bytes do not depend on which copy or which host built it.
#include <gtest/gtest.h>

#include <cmath>

namespace {

// Inputs through volatiles, so the compiler cannot fold the expression at compile time.
volatile double input_a = 1.0 + 0x1p-30, input_b = 1.0 - 0x1p-30, input_c = -1.0;

#if defined(__x86_64__) && defined(__GNUC__)
#define FMA_TARGET __attribute__((target("fma")))
#else
#define FMA_TARGET
#endif

// Compiled with FMA enabled: contracted, it would return a * b + c rounded once.
FMA_TARGET double product_plus_sum_with_fma_enabled(double a, double b, double c) { return a * b + c; }

}  // namespace

TEST(FloatContraction, CodeCompiledForFmaRoundsTheProductBeforeTheSum) {
  const double a = input_a, b = input_b, c = input_c;
  // a * b = 1 - 2^-60 exactly, which rounds to 1: the expression as written gives 0, one FMA -2^-60.
  ASSERT_EQ(std::fma(a, b, c), -0x1p-60);
#if defined(__x86_64__) && defined(__GNUC__)
  if (!__builtin_cpu_supports("fma")) {
    // The FMA copy cannot run on this host; the baseline rounding still holds.
    EXPECT_EQ(a * b + c, 0.0);
    return;
  }
#endif
  EXPECT_EQ(product_plus_sum_with_fma_enabled(a, b, c), 0.0);
}
