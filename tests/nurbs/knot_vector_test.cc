#include "nurbs/knot_vector.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "nurbs/basis.h"

namespace tangent::nurbs {
namespace {

void ExpectInvalid(int degree, std::vector<double> knots, const std::string& fragment) {
  try {
    KnotVector k(degree, std::move(knots));
    ADD_FAILURE() << "expected std::invalid_argument containing '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(KnotVectorTest, RejectsBadInputWithMessages) {
  ExpectInvalid(2, {0, 0, 0, 0.5, 0.4, 1, 1, 1}, "knot [4] = 0.4 is less than knot [3] = 0.5");
  ExpectInvalid(3, {0, 0, 1, 1}, "has 4 knots; degree 3 needs at least 8");
  ExpectInvalid(0, {0, 1}, "unsupported degree 0");
  ExpectInvalid(10, std::vector<double>(22, 0.0), "unsupported degree 10");
  ExpectInvalid(1, {0, 0, std::numeric_limits<double>::quiet_NaN(), 1}, "knot [2] is not finite");
  ExpectInvalid(1, {0, 0, INFINITY, 1}, "knot [2] is not finite");
  ExpectInvalid(2, {0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1}, "repeats 3 times; at most 2");
  ExpectInvalid(1, {0, 1, 1, 1}, "empty parametric domain");
}

TEST(KnotVectorTest, DomainClampingAndMultiplicity) {
  const KnotVector k(2, {0, 0, 0, 0.3, 0.3, 0.7, 1, 1, 1});
  EXPECT_EQ(k.num_basis(), 6);
  EXPECT_TRUE(k.IsClamped());
  EXPECT_EQ(k.Multiplicity(0.3), 2);
  EXPECT_EQ(k.domain_begin(), 0.0);
  EXPECT_EQ(k.domain_end(), 1.0);
  EXPECT_EQ(k.Breakpoints(), (std::vector<double>{0, 0.3, 0.7, 1}));
  const KnotVector open(2, {0, 1, 2, 3, 4, 5, 6});
  EXPECT_FALSE(open.IsClamped());
  EXPECT_EQ(open.domain_begin(), 2.0);
  EXPECT_EQ(open.domain_end(), 4.0);
}

TEST(KnotVectorTest, FindSpanWithAndWithoutHints) {
  const KnotVector k(2, {0, 0, 0, 0.3, 0.3, 0.7, 1, 1, 1});
  // Spans: [0,0.3) is index 2, [0.3,0.7) is 4 (index 3 is empty), [0.7,1] is 5.
  EXPECT_EQ(k.FindSpan(0.0), 2);
  EXPECT_EQ(k.FindSpan(0.29), 2);
  EXPECT_EQ(k.FindSpan(0.3), 4);
  EXPECT_EQ(k.FindSpan(0.5), 4);
  EXPECT_EQ(k.FindSpan(1.0), 5);
  EXPECT_EQ(k.FindSpan(-5.0), 2);  // Clamped to the domain.
  EXPECT_EQ(k.FindSpan(7.0), 5);
  for (int hint = -3; hint < 12; ++hint) {
    for (double t : {0.0, 0.1, 0.3, 0.31, 0.69, 0.7, 0.99, 1.0}) {
      EXPECT_EQ(k.FindSpan(t, hint), k.FindSpan(t)) << "t=" << t << " hint=" << hint;
    }
  }
}

TEST(BasisTest, PartitionOfUnityAndDerivativesByFiniteDifference) {
  const KnotVector k(3, {0, 0, 0, 0, 0.2, 0.5, 0.55, 1, 1, 1, 1});
  for (double t : {0.05, 0.3, 0.52, 0.8}) {
    const int span = k.FindSpan(t);
    BasisTable d{}, dp{}, dm{};
    BasisDerivatives(k, span, t, 2, &d);
    const double h = 1e-6;  // Central difference: truncation ~h²·N''' ~ 1e-10, rounding ~1e-10.
    BasisDerivatives(k, span, t + h, 2, &dp);
    BasisDerivatives(k, span, t - h, 2, &dm);
    double sum = 0.0, dsum = 0.0;
    for (int i = 0; i <= 3; ++i) {
      sum += d[0][static_cast<size_t>(i)];
      dsum += d[1][static_cast<size_t>(i)];
      EXPECT_NEAR((dp[0][i] - dm[0][i]) / (2 * h), d[1][i], 1e-7);
      EXPECT_NEAR((dp[1][i] - dm[1][i]) / (2 * h), d[2][i], 1e-5);
    }
    EXPECT_NEAR(sum, 1.0, 4 * std::numeric_limits<double>::epsilon());
    EXPECT_NEAR(dsum, 0.0, 1e-12);
  }
}

TEST(BasisTest, OsloRowWithEqualArgumentsIsTheBasis) {
  const KnotVector k(4, {0, 0.1, 0.2, 0.4, 0.45, 0.6, 0.8, 0.85, 0.9, 1.0, 1.2});
  for (double t : {0.45, 0.5, 0.59}) {
    const int span = k.FindSpan(t);
    BasisTable d{};
    BasisDerivatives(k, span, t, 0, &d);
    std::array<double, kMaxDegree + 1> alpha{};
    const double x[4] = {t, t, t, t};
    OsloAlphaRow(k, span, x, &alpha);
    for (int i = 0; i <= 4; ++i) EXPECT_NEAR(alpha[i], d[0][i], 1e-15);
  }
}

}  // namespace
}  // namespace tangent::nurbs
