// OpenMP glue: the engine builds and runs serial without OpenMP (every pragma is then ignored).
#pragma once

#include <algorithm>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace dem {

// A thread's own object on cache lines of its own. Threads appending to vectors that sit side
// by side in one array would write the same line at every push_back (the vectors' end
// pointers): false sharing, which makes the 2-thread pair search slower than the serial one.
template <class T>
struct alignas(64) Padded {
  T value;
};

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

// The blocks of a sum: kSumBlock items each (the last one shorter), whatever the thread count,
// so that every thread count adds the same partial sums in the same order (the same bits). A sum
// of at most kSumBlock items is the plain loop.
constexpr long kSumBlock = 16384;
inline long sum_blocks(long n) { return n <= 0 ? 0 : (n + kSumBlock - 1) / kSumBlock; }

// The sum of f(i) over [0, n): each block of kSumBlock summed in order, on any of nt threads, and
// the block sums added in block order.
template <class F>
inline double parallel_sum(long n, int nt, F&& f) {
  const long nb = sum_blocks(n);
  if (nb <= 1) {
    double s = 0;
    for (long i = 0; i < n; ++i) s += f(i);
    return s;
  }
  std::vector<double> part(static_cast<std::size_t>(nb), 0.0);
  parallel_for(nb, static_cast<int>(std::min<long>(nt, nb)), [&](long b) {
    double s = 0;
    for (long i = b * kSumBlock, end = std::min(n, (b + 1) * kSumBlock); i < end; ++i) s += f(i);
    part[static_cast<std::size_t>(b)] = s;
  });
  double s = part[0];
  for (long b = 1; b < nb; ++b) s += part[static_cast<std::size_t>(b)];
  return s;
}

// Whether pred(i) holds for some i in [0, n).
template <class F>
inline bool parallel_any(long n, int nt, F&& pred) {
  if (nt <= 1) {
    for (long i = 0; i < n; ++i)
      if (pred(i)) return true;
    return false;
  }
  bool any = false;
#pragma omp parallel for schedule(static) num_threads(nt) reduction(|| : any)
  for (long i = 0; i < n; ++i) any = any || pred(i);
  return any;
}

}  // namespace dem
