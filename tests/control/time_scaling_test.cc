#include "control/time_scaling.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

namespace vlab::control {
namespace {

TimeScaling Quintic() { return TimeScaling{TimeScalingType::kQuintic, 0.25}; }
TimeScaling Trapezoid(double a) { return TimeScaling{TimeScalingType::kTrapezoidal, a}; }

void ExpectBoundaries(const TimeScaling& sc, double T) {
  const ScalingSample s0 = EvaluateTimeScaling(sc, T, 0.0);
  const ScalingSample s1 = EvaluateTimeScaling(sc, T, T);
  EXPECT_DOUBLE_EQ(s0.s, 0.0);
  EXPECT_DOUBLE_EQ(s1.s, 1.0);
  EXPECT_DOUBLE_EQ(s0.sd, 0.0);
  EXPECT_DOUBLE_EQ(s1.sd, 0.0);
  // clamped outside [0, T]
  for (double t : {-1.0, -1e-9}) {
    const ScalingSample s = EvaluateTimeScaling(sc, T, t);
    EXPECT_EQ(s.s, 0.0);
    EXPECT_EQ(s.sd, 0.0);
    EXPECT_EQ(s.sdd, 0.0);
  }
  for (double t : {T + 1e-9, T + 5.0}) {
    const ScalingSample s = EvaluateTimeScaling(sc, T, t);
    EXPECT_EQ(s.s, 1.0);
    EXPECT_EQ(s.sd, 0.0);
    EXPECT_EQ(s.sdd, 0.0);
  }
  // continuity at the ends: values just inside approach the clamped ones
  EXPECT_NEAR(EvaluateTimeScaling(sc, T, 1e-6).s, 0.0, 1e-9);
  EXPECT_NEAR(EvaluateTimeScaling(sc, T, T - 1e-6).s, 1.0, 1e-9);
  EXPECT_NEAR(EvaluateTimeScaling(sc, T, 1e-6).sd, 0.0, 1e-4);
  EXPECT_NEAR(EvaluateTimeScaling(sc, T, T - 1e-6).sd, 0.0, 1e-4);
}

// ṡ and s̈ against central differences of s (and of ṡ), away from switches
void ExpectDerivativesMatchFiniteDifferences(const TimeScaling& sc, double T, const std::vector<double>& switches) {
  const double h = 1e-5;
  for (int k = 1; k < 200; ++k) {
    const double t = T * k / 200.0;
    bool near_switch = false;
    for (double ts : switches) near_switch |= std::abs(t - ts) < 2 * h;
    if (near_switch) continue;
    const ScalingSample s = EvaluateTimeScaling(sc, T, t);
    const ScalingSample sp = EvaluateTimeScaling(sc, T, t + h);
    const ScalingSample sm = EvaluateTimeScaling(sc, T, t - h);
    EXPECT_NEAR(s.sd, (sp.s - sm.s) / (2 * h), 1e-6) << "t = " << t;
    EXPECT_NEAR(s.sdd, (sp.sd - sm.sd) / (2 * h), 1e-6) << "t = " << t;
    EXPECT_NEAR(s.sdd, (sp.s - 2 * s.s + sm.s) / (h * h), 1e-3) << "t = " << t;
    EXPECT_GE(s.s, 0.0);
    EXPECT_LE(s.s, 1.0);
    EXPECT_GE(s.sd, 0.0);
  }
}

TEST(TimeScalingTest, QuinticBoundaries) {
  for (double T : {0.3, 1.0, 4.0}) {
    ExpectBoundaries(Quintic(), T);
    EXPECT_DOUBLE_EQ(EvaluateTimeScaling(Quintic(), T, 0.0).sdd, 0.0);
    // s̈ ≈ ±60·t/T³ next to the ends
    EXPECT_NEAR(EvaluateTimeScaling(Quintic(), T, 1e-7).sdd, 60e-7 / (T * T * T), 1e-9);
    EXPECT_NEAR(EvaluateTimeScaling(Quintic(), T, T - 1e-7).sdd, -60e-7 / (T * T * T), 1e-9);
  }
}

TEST(TimeScalingTest, QuinticClosedForm) {
  const double T = 2.0;
  for (double tau : {0.1, 0.37, 0.5, 0.81}) {
    const double s = 10 * std::pow(tau, 3) - 15 * std::pow(tau, 4) + 6 * std::pow(tau, 5);
    EXPECT_NEAR(EvaluateTimeScaling(Quintic(), T, tau * T).s, s, 1e-14);
  }
  EXPECT_NEAR(EvaluateTimeScaling(Quintic(), T, 0.5 * T).s, 0.5, 1e-15);
  EXPECT_NEAR(EvaluateTimeScaling(Quintic(), T, 0.5 * T).sd, 15.0 / (8.0 * T), 1e-14);
  EXPECT_NEAR(PeakScalingSpeed(Quintic(), T), 15.0 / (8.0 * T), 1e-15);
}

TEST(TimeScalingTest, QuinticDerivatives) { ExpectDerivativesMatchFiniteDifferences(Quintic(), 1.3, {}); }

TEST(TimeScalingTest, TrapezoidalBoundariesAndDerivatives) {
  for (double a : {0.1, 0.25, 0.5}) {
    const double T = 1.7;
    SCOPED_TRACE(a);
    ExpectBoundaries(Trapezoid(a), T);
    ExpectDerivativesMatchFiniteDifferences(Trapezoid(a), T, {a * T, T - a * T});
  }
}

TEST(TimeScalingTest, TrapezoidalPeakSpeed) {
  for (double a : {0.1, 0.25, 0.4, 0.5}) {
    const double T = 2.5;
    const double expected = 1.0 / (T * (1.0 - a));
    double peak = 0.0;
    for (int k = 0; k <= 10000; ++k) {
      peak = std::max(peak, EvaluateTimeScaling(Trapezoid(a), T, T * k / 10000.0).sd);
    }
    EXPECT_NEAR(peak, expected, 1e-12) << "a = " << a;
    EXPECT_NEAR(PeakScalingSpeed(Trapezoid(a), T), expected, 1e-15);
    // the cruise speed is reached exactly at the end of the acceleration phase
    EXPECT_NEAR(EvaluateTimeScaling(Trapezoid(a), T, a * T).sd, expected, 1e-12);
    EXPECT_NEAR(EvaluateTimeScaling(Trapezoid(a), T, 0.5 * T).s, 0.5, 1e-14);
  }
}

TEST(TimeScalingTest, ValidationNamesField) {
  try {
    ValidateTimeScaling(Quintic(), 0.0, "segment 3");
    FAIL() << "expected throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("segment 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("duration_s"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ValidateTimeScaling(Quintic(), std::nan(""), "x"), std::invalid_argument);
  for (double a : {0.0, -0.1, 0.51}) {
    try {
      ValidateTimeScaling(Trapezoid(a), 1.0, "seg");
      FAIL() << "expected throw for a = " << a;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("acceleration_fraction"), std::string::npos);
    }
  }
  EXPECT_NO_THROW(ValidateTimeScaling(Trapezoid(0.5), 1.0, "seg"));
}

}  // namespace
}  // namespace vlab::control
