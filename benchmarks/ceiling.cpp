// What 2 threads give on this machine for work with no engine in it (the 1 -> 2 thread
// target): the ceiling the engine's own speed-up is to be read against. Five loops, each run
// with 1 and 2 threads (OpenMP, each thread its own contiguous half, as the engine splits):
//
//   compute     a chain of dependent square roots per element: no memory traffic at all;
//   stream_10k  the engine's kick-drift pattern (12 arrays read, 9 written) on 10k discs'
//               arrays (1.2 MB: in the caches);
//   stream_30k, stream_100k, stream_1m  the same on 30k, 100k and 1M discs' arrays (3.6 MB,
//               12 MB, 120 MB: from the shared cache, then from memory).
//
// Each repetition is its own parallel region, as each pass of the engine's step is: a region's
// fork and join (a few microseconds here) weigh on the small loops as they do on a small world.
// Method: for each loop, `rounds` rounds; a round times the loop with 1 thread then with 2
// (interleaved, so a slow spell of the machine hits both), each time over enough repetitions to
// take about 50 ms. The speed-up is the ratio of the medians. Output: one JSON object on stdout.
//
//   build/benchmarks/dem_ceiling [rounds]      (benchmarks/speed.py runs it and reports it)
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

double now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

struct Arrays {
  std::vector<double> a[15];
  explicit Arrays(long n) {
    for (int k = 0; k < 15; ++k) a[k].assign(static_cast<std::size_t>(n), 1.0 + 1e-3 * k);
  }
};

// The kick-drift of discs [i0, i1): v += f / m h; du = v dt; x += du (the engine's loop shape).
void kick_drift(Arrays& s, long i0, long i1) {
  double* __restrict vx = s.a[0].data(); double* __restrict vy = s.a[1].data(); double* __restrict om = s.a[2].data();
  const double* __restrict fx = s.a[3].data(); const double* __restrict fy = s.a[4].data();
  const double* __restrict tq = s.a[5].data(); const double* __restrict im = s.a[6].data();
  const double* __restrict ii = s.a[7].data();
  double* __restrict ux = s.a[8].data(); double* __restrict uy = s.a[9].data(); double* __restrict up = s.a[10].data();
  double* __restrict x = s.a[11].data(); double* __restrict y = s.a[12].data(); double* __restrict phi = s.a[13].data();
  const double h = 1e-9, dt = 1e-9;
  for (long i = i0; i < i1; ++i) {
    const double v = vx[i] + fx[i] * im[i] * h, w = vy[i] + fy[i] * im[i] * h, o = om[i] + tq[i] * ii[i] * h;
    vx[i] = v; vy[i] = w; om[i] = o;
    ux[i] = v * dt; uy[i] = w * dt; up[i] = o * dt;
    x[i] += ux[i]; y[i] += uy[i]; phi[i] += up[i];
  }
}

// 32 dependent square roots per element: latency-bound arithmetic, nothing from memory.
double chain(std::vector<double>& v, long i0, long i1) {
  double s = 0;
  for (long i = i0; i < i1; ++i) {
    double q = v[static_cast<std::size_t>(i)];
    for (int k = 0; k < 32; ++k) q = std::sqrt(q + 1.5);
    v[static_cast<std::size_t>(i)] = q * 1e-3;
    s += q;
  }
  return s;
}

// Seconds per repetition of body(i0, i1) over n items with nt threads.
template <class F>
double time_per_rep(long n, int nt, int reps, F&& body) {
  const double t0 = now();
  for (int r = 0; r < reps; ++r) {
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_get_thread_num();
      body(n * t / nt, n * (t + 1) / nt);
    }
  }
  return (now() - t0) / reps;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

template <class F>
void measure(const char* name, long n, int rounds, F&& body, bool last) {
  // Repetitions for about 50 ms with one thread, from a first timing.
  const double once = time_per_rep(n, 1, 1, body);
  const int reps = std::max(1, static_cast<int>(0.05 / std::max(once, 1e-7)));
  std::vector<double> t1, t2;
  for (int r = 0; r < rounds; ++r) {
    t1.push_back(time_per_rep(n, 1, reps, body));
    t2.push_back(time_per_rep(n, 2, reps, body));
  }
  const double m1 = median(t1), m2 = median(t2);
  std::printf("  \"%s\": {\"items\": %ld, \"reps\": %d, \"t1_s\": %.6g, \"t2_s\": %.6g, \"t1_min_s\": %.6g, "
              "\"t1_max_s\": %.6g, \"t2_min_s\": %.6g, \"t2_max_s\": %.6g, \"speedup\": %.4g}%s\n",
              name, n, reps, m1, m2, *std::min_element(t1.begin(), t1.end()), *std::max_element(t1.begin(), t1.end()),
              *std::min_element(t2.begin(), t2.end()), *std::max_element(t2.begin(), t2.end()), m1 / m2, last ? "" : ",");
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
  std::printf("{\n  \"rounds\": %d, \"cpus\": %d,\n", rounds, omp_get_num_procs());
  std::vector<double> v(1 << 14, 2.0);
  measure("compute", static_cast<long>(v.size()), rounds, [&](long i0, long i1) { chain(v, i0, i1); }, false);
  Arrays small(10000);
  measure("stream_10k", 10000, rounds, [&](long i0, long i1) { kick_drift(small, i0, i1); }, false);
  Arrays mid(30000);
  measure("stream_30k", 30000, rounds, [&](long i0, long i1) { kick_drift(mid, i0, i1); }, false);
  Arrays big(100000);
  measure("stream_100k", 100000, rounds, [&](long i0, long i1) { kick_drift(big, i0, i1); }, false);
  Arrays large(1000000);
  measure("stream_1m", 1000000, rounds, [&](long i0, long i1) { kick_drift(large, i0, i1); }, true);
  std::printf("}\n");
  return 0;
}
