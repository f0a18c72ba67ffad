// Code compiled for a wider vector than the build's (the kernel list holds each width's): AVX2,
// four doubles a vector, without FMA; AVX-512, eight (512-bit, which GCC otherwise avoids), whose
// FMA is never used for a contraction (-ffp-contract=off).
#pragma once

#define DEM_TARGET_AVX2 __attribute__((target("avx2")))
#define DEM_TARGET_AVX512 __attribute__((target("avx512f,avx512dq,avx512vl,prefer-vector-width=512")))
