// The discharge's peak ratios from samples fed one at a time (PeakTracker): the largest sample
// and the largest moving average over `win` samples, against the same quantities computed here
// over the whole series kept (the definition in docs/outputs.md). That the outputs keep their
// bits is checked by comparing whole runs with the engine before (benchmarks/README.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "run/discharge.hpp"

namespace dem {
namespace {

TEST(PeakTracker, GivesThePeaksOfTheWholeSeries) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> load(0.0, 1e6);
  for (std::size_t win : {1u, 2u, 5u, 40u}) {
    for (std::size_t n : {0u, 1u, 3u, 40u, 41u, 1000u}) {
      std::vector<double> v(n);
      for (double& x : v) x = load(rng);
      PeakTracker t;
      for (double x : v) t.add(x, win);
      double raw = 0, windowed = 0;
      for (std::size_t e = 0; e < n; ++e) {  // every window that fits, summed afresh
        raw = std::max(raw, v[e]);
        if (e + 1 < win) continue;
        double sum = 0;
        for (std::size_t k = e + 1 - win; k <= e; ++k) sum += v[k];
        windowed = std::max(windowed, sum / static_cast<double>(win));
      }
      EXPECT_EQ(t.raw, raw) << "win " << win << ", n " << n;
      // A running sum rounds differently from one summed afresh: equal to a few ulps.
      EXPECT_NEAR(t.windowed, windowed, 1e-9 * windowed) << "win " << win << ", n " << n;
      EXPECT_EQ(t.last.size(), n ? win : 0u) << "only the last win samples are kept";
      if (n < win) {
        EXPECT_EQ(t.windowed, 0.0) << "no window filled yet";
      }
    }
  }
}

}  // namespace
}  // namespace dem
