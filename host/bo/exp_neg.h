// exp(-r) for r >= 0 as straight-line arithmetic, so that a loop over many r runs in vector
// lanes: the Matern kernel's exponential, evaluated n times per GP prediction. libm's exp
// takes a call and ~20 cycles a value and was 14 % of the triangle stage's time (the demo,
// perf); inlined into a loop compiled for AVX2 this runs 4 lanes wide.
//
// e^x = 2^k e^t with k = round(x / ln 2) and t = x - k ln 2 in [-ln 2 / 2, ln 2 / 2] (ln 2
// split in two so that k ln 2_hi is exact: Cody & Waite, fdlibm's constants); e^t by its
// Taylor series to t^13 (the remainder is below 5e-18 relative); 2^k written into the
// exponent's bits. Within 1 ulp of libm's exp over [0, 708] (tests/bo); 0 for r > 708,
// where e^-r is below 2^-1021 and no kernel value can be told from 0.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace uvpress::bo {

inline double exp_neg(double r) {
  const double x = -std::min(r, 708.0);
  constexpr double kShift = 0x1.8p52;  // adding it rounds to an integer in the low bits
  const double kd = x * 1.4426950408889634 + kShift;
  const double k = kd - kShift;
  const double t = (x - k * 6.93147180369123816490e-01) - k * 1.90821492927058770002e-10;
  double p = 1.0 / 6227020800.0;  // 1/13!
  p = p * t + 1.0 / 479001600.0;
  p = p * t + 1.0 / 39916800.0;
  p = p * t + 1.0 / 3628800.0;
  p = p * t + 1.0 / 362880.0;
  p = p * t + 1.0 / 40320.0;
  p = p * t + 1.0 / 5040.0;
  p = p * t + 1.0 / 720.0;
  p = p * t + 1.0 / 120.0;
  p = p * t + 1.0 / 24.0;
  p = p * t + 1.0 / 6.0;
  p = p * t + 0.5;
  p = p * t + 1.0;
  p = p * t + 1.0;
  // kd's bits are those of 1.5 * 2^52 plus k (its unit in the last place is 1 there), and
  // k >= -1021 as x >= -708.
  int64_t bits;
  std::memcpy(&bits, &kd, sizeof bits);
  const int64_t scale_bits = (bits - 0x4338000000000000 + 1023) << 52;
  double scale;
  std::memcpy(&scale, &scale_bits, sizeof scale);
  return r > 708.0 ? 0.0 : p * scale;
}

}  // namespace uvpress::bo
