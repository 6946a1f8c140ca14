// The design file format: parsing, linting and one-line errors.
#include <gtest/gtest.h>

#include <cmath>

#include "design_files.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"

using namespace fabatlas;
using fabatlas::testing::TempDesign;

namespace {

const char* kSphere = R"(name: ball
voxel_size: 0.1
parameters:
  r: {type: real, min: 0.5, max: 2, default: 1}
  n: {type: integer, min: 1, max: 4}
  finish: {type: enum, values: [matte, glossy], default: glossy}
variables:
  d: {min: 0, max: 10, default: 2}
constraints:
  - d == 2 * r
tree: {op: sphere, radius: r}
checks: [watertight, {type: stands, margin: 0.1}]
properties: [volume, bbox]
)";

// Loads `text` and returns the error message (empty if it loaded).
std::string ErrorOf(const std::string& text) {
  auto path = TempDesign(text);
  try {
    design::LoadDesign(path);
  } catch (const InputError& e) {
    std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "error must be one line: " << msg;
    EXPECT_NE(msg.find(path.string()), std::string::npos) << "error must name the file: " << msg;
    return msg;
  }
  return "";
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return text.replace(pos, from.size(), to);
}

}  // namespace

TEST(DesignModel, ParsesEveryPart) {
  design::Design d = design::LoadDesign(TempDesign(kSphere));
  EXPECT_EQ(d.name, "ball");
  EXPECT_DOUBLE_EQ(d.voxel_size, 0.1);
  ASSERT_EQ(d.exposed.size(), 3u);
  EXPECT_EQ(d.exposed[0].kind, design::ParameterKind::kReal);
  EXPECT_EQ(d.exposed[1].kind, design::ParameterKind::kInteger);
  EXPECT_DOUBLE_EQ(d.exposed[1].default_value, 3);  // middle of [1,4], rounded
  EXPECT_EQ(d.exposed[2].kind, design::ParameterKind::kEnumerated);
  EXPECT_DOUBLE_EQ(d.exposed[2].default_value, 1);  // "glossy"
  ASSERT_EQ(d.constraints.size(), 1u);
  EXPECT_EQ(d.constraints[0].relation, design::Relation::kEqual);
  EXPECT_EQ(d.tree.op, "sphere");
  ASSERT_EQ(d.checks.size(), 2u);
  EXPECT_EQ(d.checks[1].type, "stands");
}

TEST(DesignModel, PointsTakeDefaultsAndRejectBadValues) {
  design::Design d = design::LoadDesign(TempDesign(kSphere));
  design::Point u = design::ParsePoint(d, "r=1.5,finish=matte", "--at");
  EXPECT_DOUBLE_EQ(u["r"], 1.5);
  EXPECT_DOUBLE_EQ(u["n"], 3);
  EXPECT_DOUBLE_EQ(u["finish"], 0);
  EXPECT_THROW(design::ParsePoint(d, "r=5", "--at"), InputError);    // out of range
  EXPECT_THROW(design::ParsePoint(d, "r=nan", "--at"), InputError);  // NaN
  EXPECT_THROW(design::ParsePoint(d, "q=1", "--at"), InputError);    // unknown name
  EXPECT_THROW(design::ParsePoint(d, "n=1.5", "--at"), InputError);  // not whole
  EXPECT_THROW(design::ParsePoint(d, "r", "--at"), InputError);      // not name=value
}

TEST(DesignModel, MalformedYamlNamesLineAndColumn) {
  std::string msg = ErrorOf("name: x\nparameters: {r: [1, 2\n");
  EXPECT_NE(msg.find("malformed YAML"), std::string::npos) << msg;
  EXPECT_NE(msg.find(":3:"), std::string::npos) << msg;
}

TEST(DesignModel, UnknownNodeType) {
  std::string msg = ErrorOf(Replace(kSphere, "op: sphere", "op: sphear"));
  EXPECT_NE(msg.find(":11:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown node type 'sphear'"), std::string::npos) << msg;
}

TEST(DesignModel, UnknownNameInExpression) {
  std::string msg = ErrorOf(Replace(kSphere, "radius: r}", "radius: r * k}"));
  EXPECT_NE(msg.find("unknown name 'k'"), std::string::npos) << msg;
  msg = ErrorOf(Replace(kSphere, "d == 2 * r", "d == 2 * radius"));
  EXPECT_NE(msg.find("unknown name 'radius'"), std::string::npos) << msg;
  EXPECT_NE(msg.find(":10:"), std::string::npos) << msg;
}

TEST(DesignModel, NaNAndInfiniteNumbers) {
  EXPECT_NE(ErrorOf(Replace(kSphere, "min: 0.5", "min: .nan")).find("NaN"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "voxel_size: 0.1", "voxel_size: .inf")).find("infinite"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "max: 10", "max: ten")).find("must be a number"), std::string::npos);
}

TEST(DesignModel, MinAboveMax) {
  std::string msg = ErrorOf(Replace(kSphere, "min: 0.5, max: 2", "min: 3, max: 2"));
  EXPECT_NE(msg.find("min > max"), std::string::npos) << msg;
  EXPECT_NE(msg.find(":4:"), std::string::npos) << msg;
}

TEST(DesignModel, DefaultOutsideRange) {
  EXPECT_NE(ErrorOf(Replace(kSphere, "default: 1}", "default: 7}")).find("outside [min, max]"), std::string::npos);
}

TEST(DesignModel, MissingMeshFile) {
  std::string msg = ErrorOf(Replace(kSphere, "{op: sphere, radius: r}", "{op: mesh, file: nowhere.stl}"));
  EXPECT_NE(msg.find("does not exist"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nowhere.stl"), std::string::npos) << msg;
}

TEST(DesignModel, WrongArgumentsAndChildren) {
  EXPECT_NE(ErrorOf(Replace(kSphere, "radius: r}", "radius: r, colour: 3}")).find("unknown argument 'colour'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "{op: sphere, radius: r}", "{op: box}")).find("needs 'size'"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "{op: sphere, radius: r}", "{op: union, children: [{op: sphere, radius: r}]}"))
                .find("at least 2 children"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "{op: sphere, radius: r}", "{op: box, size: [1, 2]}")).find("[x, y, z]"),
            std::string::npos);
}

TEST(DesignModel, BadConstraintsChecksAndProperties) {
  EXPECT_NE(ErrorOf(Replace(kSphere, "d == 2 * r", "d = 2 * r")).find("needs one of"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "[watertight,", "[watertite,")).find("unknown check type"), std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "[volume, bbox]", "[volume, colour]")).find("unknown property"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "name: ball", "name: ball\ncolour: red")).find("unknown key 'colour'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(Replace(kSphere, "n: {type: integer", "r: {type: integer")).find("declared twice"),
            std::string::npos);
}

TEST(DesignModel, NotAMapAndMissingFile) {
  EXPECT_NE(ErrorOf("- just\n- a list\n").find("must be a YAML map"), std::string::npos);
  EXPECT_NE(ErrorOf("").find("must be a YAML map"), std::string::npos);
  EXPECT_THROW(design::LoadDesign("/nonexistent/design.yaml"), InputError);
}

TEST(DesignModel, ExampleDesignsLoad) {
  for (const auto& entry : std::filesystem::directory_iterator(fabatlas::testing::SourceDir() / "configs/designs")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    design::Design d = design::LoadDesign(entry.path());
    EXPECT_FALSE(d.exposed.empty());
  }
}
