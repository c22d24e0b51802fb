// SHADOWTILES_ISA_CLONES: a hot function compiled twice, for x86-64-v3 (popcnt, lzcnt, BMI1/2,
// AVX2, FMA: Haswell, Zen and later) and for the baseline, the copy picked once when the library loads
// (GNU ifunc), the way Embree dispatches its kernels. The installed library still runs on any
// x86-64. Used where it measured a gain: DAG-MH point and PCF lookups and batch walks (popcounts
// and variable shifts on every step): +5-8% point rows, +9-11% PCF 3x3 on fzk_haus (docs/client.md);
// the DAG-MH encoder's grid search (an fma per multiplier: one instruction instead of a libm call;
// docs/build-time.md); build_mh's bottom-up pass (the `surfaces` encoders' thread-s -17 to -28 %,
// docs/build-time.md, session 44). MH and CPVS lookups gained nothing, nor did the entry rule, the
// second-layer cap pass or the MMH merge and MH encoder on full-depth trees (session 44).
// GCC only (clang 14's clones are young; the fuzz build is clang). Off with SHADOWTILES_NO_ISA_CLONES
// (the sanitized build sets it, so it checks the baseline copies).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(SHADOWTILES_NO_ISA_CLONES)
#define SHADOWTILES_ISA_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SHADOWTILES_ISA_CLONES
#endif
