// OpenMP glue: the engine builds and runs serial without OpenMP (every pragma is then ignored).
#pragma once

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dem {

inline int omp_thread_index() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

// Start of block t of n items split into nt nearly equal contiguous blocks (block_start(.., nt) = n).
inline int block_start(int n, int nt, int t) {
  return static_cast<int>(static_cast<long long>(n) * t / nt);
}

}  // namespace dem
