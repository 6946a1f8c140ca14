#include "fabatlas/sampling/design_space.h"

#include <gtest/gtest.h>

#include "fabatlas/error.h"

namespace fabatlas::sampling {
namespace {

TEST(SamplingDesignSpace, BootstrapCellsPerKind) {
  DesignSpace space({{"r", DimensionKind::kReal, 1.0, 2.0, {}},
                     {"n", DimensionKind::kInteger, 2.0, 4.0, {}},
                     {"m", DimensionKind::kEnumerated, 0, 0, {"a", "b", "c", "d", "e", "f", "g"}},
                     {"k", DimensionKind::kInteger, -10.0, 10.0, {}}},
                    5);
  EXPECT_EQ(space.cell_count(0), 5);
  EXPECT_EQ(space.cell_count(1), 2);  // 3 values -> 2 cells, never more than values - 1
  EXPECT_EQ(space.cell_count(2), 5);  // 7 values -> min(5, 6)
  EXPECT_EQ(space.cell_count(3), 5);
  // Integer grid lines are whole values spread as evenly as possible.
  std::vector<std::int64_t> lines;
  for (int j = 0; j <= 5; ++j) lines.push_back(space.grid_key(3, j));
  EXPECT_EQ(lines, (std::vector<std::int64_t>{-10, -6, -2, 2, 6, 10}));
  EXPECT_EQ(space.grid_key(2, 5), 6);
  // Real keys are dyadic: grid line j at j * 2^40, values exact at the ends.
  EXPECT_EQ(space.grid_key(0, 3), std::int64_t{3} << kDyadicBits);
  EXPECT_DOUBLE_EQ(space.value(0, space.grid_key(0, 0)), 1.0);
  EXPECT_DOUBLE_EQ(space.value(0, space.grid_key(0, 5)), 2.0);
  EXPECT_DOUBLE_EQ(space.value(0, std::int64_t{1} << (kDyadicBits - 1)), 1.1);  // half a cell of 0.2
  EXPECT_DOUBLE_EQ(space.value(1, 3), 3.0);
  // Discrete splits stop at adjacent values; real cells halve kDyadicBits times.
  EXPECT_TRUE(space.can_split(1, 2, 4));
  EXPECT_EQ(space.split_key(1, 2, 4), 3);
  EXPECT_FALSE(space.can_split(1, 2, 3));
  EXPECT_TRUE(space.can_split(0, 0, 2));
  EXPECT_FALSE(space.can_split(0, 0, 1));
  // Lengths: parameter units for reals, value steps for discrete dimensions.
  EXPECT_DOUBLE_EQ(space.length(0, space.key_lo(0), space.key_hi(0)), 1.0);
  EXPECT_DOUBLE_EQ(space.length(2, 0, 6), 6.0);
}

TEST(SamplingDesignSpace, RejectsBadDimensionsWithOneLineMessages) {
  auto bad = [](std::vector<Dimension> dims, int sub = 5) {
    try {
      DesignSpace s(std::move(dims), sub);
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos);
      return m;
    }
    return std::string("no error");
  };
  EXPECT_NE(bad({{"r", DimensionKind::kReal, 2.0, 1.0, {}}}).find("'r'"), std::string::npos);
  EXPECT_NE(bad({{"n", DimensionKind::kInteger, 0.5, 3.0, {}}}).find("whole numbers"), std::string::npos);
  EXPECT_NE(bad({{"m", DimensionKind::kEnumerated, 0, 0, {"only"}}}).find("two values"), std::string::npos);
  EXPECT_NE(bad({{"a", DimensionKind::kReal, 0, 1, {}}, {"a", DimensionKind::kReal, 0, 1, {}}}).find("duplicate"),
            std::string::npos);
  EXPECT_NE(bad({{"a", DimensionKind::kReal, 0, 1, {}}}, 0).find("subdivisions"), std::string::npos);
  std::vector<Dimension> too_many;
  for (int i = 0; i <= kMaxDimensions; ++i)
    too_many.push_back({"d" + std::to_string(i), DimensionKind::kReal, 0, 1, {}});
  EXPECT_NE(bad(too_many).find("17 exposed parameters, at most 16"), std::string::npos);
  too_many.pop_back();  // 16 dimensions are fine
  EXPECT_EQ(bad(too_many), "no error");
}

}  // namespace
}  // namespace fabatlas::sampling
