#include "sim/so3.h"

#include "sim/units.h"
#include "tests/test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace shutterlab {
namespace {

// Double rounding over a handful of operations.
constexpr double kTightTol = 1e-12;

TEST(SO3, ExpOfZeroIsIdentity) {
  const Eigen::Quaterniond q = ExpSO3(Eigen::Vector3d::Zero());
  EXPECT_NEAR(q.w(), 1.0, 0.0);
  EXPECT_EQ(q.vec().norm(), 0.0);
}

TEST(SO3, ExpMatchesAngleAxis) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  for (double angle : {1e-12, 1e-6, 0.3, 2.0, kPi - 1e-9, kPi}) {
    const Eigen::Quaterniond expected(Eigen::AngleAxisd(angle, axis));
    test::ExpectRotationNear(ExpSO3(axis * angle), expected, kTightTol);
  }
}

TEST(SO3, LogExpRoundTripOnEdgeCasesAndRandomSweep) {
  std::mt19937_64 rng(42);
  std::normal_distribution<double> normal;
  std::vector<Eigen::Vector3d> cases = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1e-12, 0, 0),
                                        Eigen::Vector3d(0, 0, kPi - 1e-9),
                                        Eigen::Vector3d(0.3, -0.2, 0.1)};
  for (int i = 0; i < 1000; ++i) {
    Eigen::Vector3d v(normal(rng), normal(rng), normal(rng));
    if (v.norm() > kPi - 1e-6) v *= (kPi - 1e-6) / v.norm();
    cases.push_back(v);
  }
  for (const auto& v : cases) {
    EXPECT_LE((LogSO3(ExpSO3(v)) - v).norm(), 1e-9) << v.transpose();
  }
}

TEST(SO3, LogOfNegatedQuaternionIsTheSame) {
  const Eigen::Quaterniond q = ExpSO3(Eigen::Vector3d(0.4, 0.1, -0.7));
  Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  EXPECT_LE((LogSO3(q) - LogSO3(minus_q)).norm(), kTightTol);
}

TEST(SO3, LogNearPiStaysWithinPi) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(LogSO3(q).norm(), kPi, 1e-12);
}

TEST(SO3, HatIsCrossProduct) {
  const Eigen::Vector3d a(1, 2, 3), b(-0.5, 4, 0.25);
  EXPECT_LE((Hat(a) * b - a.cross(b)).norm(), kTightTol);
}

TEST(SO3, AngleFromTraceRecoversRotationAngle) {
  const Eigen::Matrix3d r = RotationZYX(0.01, -0.02, 0.005);
  const double expected = Eigen::AngleAxisd(r).angle();
  EXPECT_NEAR(AngleFromTrace(r), expected, 1e-9);
  EXPECT_TRUE(IsRotationMatrix(r));
  EXPECT_FALSE(IsRotationMatrix(2.0 * r));
  EXPECT_FALSE(IsRotationMatrix(-r));  // det -1
}

}  // namespace
}  // namespace shutterlab
