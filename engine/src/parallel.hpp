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

// f(i) for i in [0, n): a plain loop for one thread (no OpenMP call at all: small worlds pay
// nothing), static blocks otherwise. For loops whose iterations are independent.
template <class F>
inline void parallel_for(long n, int nt, F&& f) {
  if (nt <= 1) {
    for (long i = 0; i < n; ++i) f(i);
    return;
  }
#pragma omp parallel for schedule(static) num_threads(nt)
  for (long i = 0; i < n; ++i) f(i);
}

}  // namespace dem
