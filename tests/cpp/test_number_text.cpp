// Numbers as text (io/files.hpp): fmt17 and digits17 write the bytes of printf's "%.17g", the
// format every output file has always had. glibc's printf is the independent reference here:
// random bit patterns (every exponent, subnormals, NaN payloads) and the edge cases.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "io/files.hpp"

using namespace dem;

namespace {
std::string printf17(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string streamed(double v) {
  std::ostringstream o;
  o << digits17(v);
  return o.str();
}
}  // namespace

TEST(NumberText, EdgeCasesAreThoseOfPrintf) {
  using lim = std::numeric_limits<double>;
  const double cases[] = {0.0, -0.0, 1.0, -1.0, 0.1, 1.0 / 3.0, 1e16, 1e17, 123456789012345678.0,
                          99999999999999999.0, 1e-4, 1e-5, 0.0001234, 5e-324, -5e-324, lim::min(),
                          -lim::min(), lim::max(), -lim::max(), lim::epsilon(), lim::infinity(),
                          -lim::infinity(), lim::quiet_NaN(), -lim::quiet_NaN(), 980.0, -9.81, 2.5e-5};
  for (double v : cases) {
    EXPECT_EQ(fmt17(v), printf17(v)) << "bits of " << printf17(v);
    EXPECT_EQ(streamed(v), printf17(v)) << "bits of " << printf17(v);
  }
}

TEST(NumberText, RandomBitPatternsAreThoseOfPrintf) {
  std::mt19937_64 gen(20261126);
  std::uniform_real_distribution<double> u(-1e4, 1e4);
  int wrong = 0;
  for (int i = 0; i < 50000 && wrong < 5; ++i) {
    std::uint64_t bits = gen();
    double any;
    std::memcpy(&any, &bits, sizeof any);
    // Any double, and values of a run's magnitudes (positions, forces, times).
    for (double v : {any, u(gen), std::ldexp(u(gen), -static_cast<int>(gen() % 40))}) {
      const std::string want = printf17(v);
      if (fmt17(v) != want || streamed(v) != want) {
        ++wrong;
        ADD_FAILURE() << want << ": fmt17 " << fmt17(v) << ", digits17 " << streamed(v);
      }
    }
  }
}
