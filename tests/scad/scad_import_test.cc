// Reading OpenSCAD Customizer annotations by the rules of the OpenSCAD User
// Manual ("Customizer") and importing models as designs: every widget form,
// groups, [Hidden], descriptions, malformed lines, Debian's Parametric
// examples, parameter sets as presets.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>

#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/scad/evaluate_model.h"
#include "fabatlas/scad/import_design.h"
#include "fabatlas/testing/paths.h"

namespace {

using fabatlas::scad::CustomizerModel;
using fabatlas::scad::CustomizerParameter;
using fabatlas::scad::ScadValue;
using W = CustomizerParameter::Widget;

const CustomizerParameter& Find(const CustomizerModel& m, const std::string& name) {
  for (const auto& p : m.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

bool Has(const CustomizerModel& m, const std::string& name) {
  for (const auto& p : m.parameters)
    if (p.name == name) return true;
  return false;
}

// The manual's widget examples, verbatim in form.
const char* kManual = R"(// combo box for number
Numbers=2; // [0, 1, 2, 3]

// combo box for string
Strings="foo"; // [foo, bar, baz]

//labeled combo box for numbers
Labeled_values=10; // [10:S, 20:M, 30:L]

//labeled combo box for string
Labeled_value="S"; // [S:Small, M:Medium, L:Large]

/* [Sliders] */
// slider widget for number with max. value
sliderWithMax =34; // [50]

// slider widget for number in range
sliderWithRange =34; // [10:100]

//step slider for number
stepSlider=2; //[0:5:100]

// slider widget for number in range
sliderCentered =0; // [-10:0.1:10]

/*[ Other widgets ]*/
//description
Variable = true;

// spinbox with step size 1
Spinbox= 5;

//Text box for vector with more than 4 elements
Vector6=[12,34,44,43,23,23];

// Text box for string
String="hello";

expression = 12 + 0.5;

/* [Hidden] */
secret = 3; // [0:10]

/* [Back] */
$fn = 20;
module __Customizer_Limit__ () {}
after_brace = 4; // [0:10]
)";

TEST(Customizer, EveryWidgetOfTheManual) {
  CustomizerModel m = fabatlas::scad::ReadCustomizer(kManual, "manual.scad");
  EXPECT_TRUE(m.warnings.empty()) << m.warnings[0];

  const auto& numbers = Find(m, "Numbers");
  EXPECT_EQ(numbers.widget, W::kDropdown);
  ASSERT_EQ(numbers.options.size(), 4u);
  EXPECT_EQ(numbers.options[3].value.type, ScadValue::Type::kNumber);
  EXPECT_EQ(numbers.options[3].value.number, 3);
  EXPECT_EQ(numbers.description, "combo box for number");

  const auto& strings = Find(m, "Strings");
  EXPECT_EQ(strings.widget, W::kDropdown);
  ASSERT_EQ(strings.options.size(), 3u);
  EXPECT_EQ(strings.options[1].value.type, ScadValue::Type::kString);
  EXPECT_EQ(strings.options[1].value.text, "bar");

  const auto& labelled = Find(m, "Labeled_values");
  ASSERT_EQ(labelled.options.size(), 3u);
  EXPECT_EQ(labelled.options[1].value.number, 20);
  EXPECT_EQ(labelled.options[1].label, "M");
  const auto& labelled_s = Find(m, "Labeled_value");
  EXPECT_EQ(labelled_s.options[2].value.text, "L");
  EXPECT_EQ(labelled_s.options[2].label, "Large");

  const auto& max_only = Find(m, "sliderWithMax");
  EXPECT_EQ(max_only.widget, W::kSlider);
  EXPECT_EQ(max_only.min, 0);
  EXPECT_EQ(max_only.max, 50);
  EXPECT_EQ(max_only.group, "Sliders");
  const auto& range = Find(m, "sliderWithRange");
  EXPECT_EQ(range.min, 10);
  EXPECT_EQ(range.max, 100);
  EXPECT_EQ(range.step, 0);
  const auto& step = Find(m, "stepSlider");
  EXPECT_EQ(step.step, 5);
  EXPECT_EQ(step.max, 100);
  const auto& centred = Find(m, "sliderCentered");
  EXPECT_EQ(centred.min, -10);
  EXPECT_DOUBLE_EQ(centred.step, 0.1);

  // No annotation: check box, spin box, text boxes: parameters without a widget.
  EXPECT_EQ(Find(m, "Variable").widget, W::kNone);
  EXPECT_EQ(Find(m, "Variable").value.type, ScadValue::Type::kBoolean);
  EXPECT_EQ(Find(m, "Variable").group, "Other widgets");
  EXPECT_EQ(Find(m, "Spinbox").widget, W::kNone);
  EXPECT_EQ(Find(m, "Vector6").value.type, ScadValue::Type::kVector);
  EXPECT_EQ(Find(m, "String").value.text, "hello");
  // Expressions are not parameters; [Hidden] hides; nothing after the first '{'.
  EXPECT_FALSE(Has(m, "expression"));
  EXPECT_TRUE(Find(m, "secret").hidden);
  EXPECT_FALSE(Find(m, "$fn").hidden);
  EXPECT_FALSE(Has(m, "after_brace"));
}

TEST(Customizer, MalformedAnnotationsAreWarningsNamingTheLine) {
  const char* text =
      "a = 5; // [10:1]\n"          // 1: min > max
      "b = 5; // [0:0:10]\n"        // 2: step 0
      "c = 5; // [0:10\n"           // 3: unterminated
      "d = \"x\"; // [0:10]\n"      // 4: slider on a string
      "e = 7; // [1, 2, 3]\n"       // 5: value not among the options
      "f = 5; // [1:2:3:4]\n"       // 6: too many parts
      "g = 5; // [0:10]\n"          // 7: fine
      "h = 5; // just a comment\n"  // 8: not an annotation, no warning
      "i = 50; // [0:10]\n";        // 9: value outside the slider
  CustomizerModel m = fabatlas::scad::ReadCustomizer(text, "bad.scad");
  ASSERT_EQ(m.warnings.size(), 7u);
  const int lines[] = {1, 2, 3, 4, 5, 6, 9};
  for (int k = 0; k < 7; ++k)
    EXPECT_EQ(m.warnings[k].rfind("bad.scad:" + std::to_string(lines[k]) + ": ", 0), 0u) << m.warnings[k];
  EXPECT_NE(m.warnings[0].find("min > max"), std::string::npos) << m.warnings[0];
  EXPECT_NE(m.warnings[0].find("kept fixed at 5"), std::string::npos) << m.warnings[0];
  for (const char* name : {"a", "b", "c", "d", "e", "f", "h", "i"}) EXPECT_EQ(Find(m, name).widget, W::kNone) << name;
  EXPECT_EQ(Find(m, "g").widget, W::kSlider);
}

// `use <file>` and `include <file>` end at their '>' without a ';': the
// parameter after one is a parameter (MCAD wrappers start with `use`).
TEST(Customizer, ParametersAfterUseAndIncludeAreRead) {
  const char* text =
      "use <MCAD/involute_gears.scad>\n/* [Gear] */\n// Number of teeth\nteeth = 17; // [8:40]\n"
      "include <MCAD/units.scad>\nsize = 3; // [1:5]\ncube([teeth, size, 1]);\n";
  CustomizerModel m = fabatlas::scad::ReadCustomizer(text, "gear.scad");
  EXPECT_TRUE(m.warnings.empty());
  ASSERT_EQ(m.parameters.size(), 2u);
  EXPECT_EQ(Find(m, "teeth").widget, W::kSlider);
  EXPECT_EQ(Find(m, "teeth").group, "Gear");
  EXPECT_EQ(Find(m, "teeth").description, "Number of teeth");
  EXPECT_EQ(Find(m, "size").widget, W::kSlider);
}

TEST(Customizer, QuotingForOpenScad) {
  EXPECT_EQ(fabatlas::scad::QuoteScadString("square"), "\"square\"");
  EXPECT_EQ(fabatlas::scad::QuoteScadString("say \"hi\" \\o/"), "\"say \\\"hi\\\" \\\\o/\"");
  EXPECT_EQ(fabatlas::scad::FormatScadNumber(0.1), "0.1");
  EXPECT_EQ(fabatlas::scad::FormatScadNumber(120), "120");
  EXPECT_EQ(fabatlas::scad::FormatScadNumber(-2.5), "-2.5");
  // A quoted dropdown value with an escaped quote reads back unescaped.
  CustomizerModel m = fabatlas::scad::ReadCustomizer("s = \"a\"; // [\"a\", \"b \\\"c\\\", d\"]\n", "q.scad");
  ASSERT_TRUE(m.warnings.empty()) << m.warnings[0];
  ASSERT_EQ(Find(m, "s").options.size(), 2u);
  EXPECT_EQ(Find(m, "s").options[1].value.text, "b \"c\", d");
}

TEST(Customizer, DebianParametricExamples) {
  const std::filesystem::path dir = "/usr/share/openscad/examples/Parametric";
  if (!std::filesystem::exists(dir / "sign.scad")) GTEST_SKIP() << "openscad examples not installed";
  auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  CustomizerModel sign = fabatlas::scad::ReadCustomizer(read(dir / "sign.scad"), "sign.scad");
  EXPECT_TRUE(sign.warnings.empty());
  // resolution, radius, height, Message, To (and not $fn = resolution, an expression).
  ASSERT_EQ(sign.parameters.size(), 5u);
  EXPECT_EQ(Find(sign, "resolution").options.size(), 5u);
  EXPECT_EQ(Find(sign, "radius").min, 60);
  EXPECT_EQ(Find(sign, "radius").max, 200);
  EXPECT_EQ(Find(sign, "Message").options[1].value.text, "Happy Birthday!");
  EXPECT_EQ(Find(sign, "Message").group, "Content To be written");
  EXPECT_EQ(Find(sign, "To").widget, W::kNone);
  EXPECT_EQ(Find(sign, "height").description, "Total height of the sign");

  CustomizerModel candle = fabatlas::scad::ReadCustomizer(read(dir / "candleStand.scad"), "candleStand.scad");
  EXPECT_TRUE(candle.warnings.empty());
  EXPECT_EQ(candle.parameters.size(), 12u);  // length .. widthOfRing, before the first '{'
  const auto& length = Find(candle, "length");
  ASSERT_EQ(length.options.size(), 3u);
  EXPECT_EQ(length.options[0].value.number, 70);
  EXPECT_EQ(length.options[0].label, "large");
  EXPECT_EQ(Find(candle, "count").max, 14);
  EXPECT_EQ(Find(candle, "centerCandle").value.type, ScadValue::Type::kBoolean);
  EXPECT_EQ(Find(candle, "widthOfRing").group, "Properties of Ring");

  // Imported as designs: exposed parameters, enum choices, presets.
  fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(dir / "candleStand.scad", {});
  EXPECT_EQ(s.exposed, (std::vector<std::string>{"length", "count"}));
  EXPECT_EQ(s.presets, 4);
  fabatlas::design::Design d = fabatlas::design::ParseDesign(s.design_yaml, dir / "candleStand.yaml");
  ASSERT_EQ(d.exposed.size(), 2u);
  EXPECT_EQ(d.exposed[0].kind, fabatlas::design::ParameterKind::kEnumerated);
  EXPECT_EQ(d.exposed[0].labels, (std::vector<std::string>{"large", "medium", "small"}));
  EXPECT_EQ(d.exposed[0].default_value, 1);  // the model's 50 = medium
  EXPECT_EQ(d.exposed[1].kind, fabatlas::design::ParameterKind::kInteger);
  ASSERT_EQ(d.presets.size(), 4u);
  EXPECT_EQ(d.presets[3].name, "Large");
  EXPECT_EQ(d.presets[3].values.at("length"), 0);
  EXPECT_EQ(d.presets[2].values.at("count"), 5);  // "With Ball"

  fabatlas::scad::ImportSummary sg = fabatlas::scad::ImportScad(dir / "sign.scad", {});
  EXPECT_EQ(sg.exposed, (std::vector<std::string>{"resolution", "radius", "height", "Message"}));
  fabatlas::design::Design ds = fabatlas::design::ParseDesign(sg.design_yaml, dir / "sign.yaml");
  EXPECT_EQ(ds.exposed[3].labels[4], "Thank You");
  EXPECT_EQ(ds.exposed[0].labels[2], "30");
}

TEST(Import, ExposeAndItsErrors) {
  auto dir = fabatlas::testing::FreshTempDir("scad-import");
  std::ofstream(dir / "m.scad")
      << "/* [A] */\nw = 10; // [1:20]\nflag = true;\nfree = 3;\n/* [Hidden] */\nh = 2; // [1:5]\ncube([w, h, 1]);\n";
  fabatlas::scad::ImportOptions o;
  o.expose = {"flag", "h"};
  fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(dir / "m.scad", o);
  EXPECT_EQ(s.exposed, (std::vector<std::string>{"flag", "h"}));  // a boolean and a hidden slider, by name
  fabatlas::design::Design d = fabatlas::design::ParseDesign(s.design_yaml, dir / "m.yaml");
  EXPECT_EQ(d.exposed[0].labels, (std::vector<std::string>{"false", "true"}));
  EXPECT_EQ(d.exposed[0].default_value, 1);
  o.expose = {"free"};
  try {
    fabatlas::scad::ImportScad(dir / "m.scad", o);
    ADD_FAILURE() << "a parameter without a range was exposed";
  } catch (const fabatlas::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("m.scad:4: --expose free"), std::string::npos) << e.what();
  }
  o.expose = {"nope"};
  EXPECT_THROW(fabatlas::scad::ImportScad(dir / "m.scad", o), fabatlas::InputError);
  // No annotation: nothing exposed, a one-sample design with the numbers fixed.
  std::ofstream(dir / "none.scad") << "a = 1;\ncube(a);\n";
  fabatlas::scad::ImportSummary none = fabatlas::scad::ImportScad(dir / "none.scad", {});
  EXPECT_TRUE(none.exposed.empty());
  EXPECT_EQ(none.fixed, (std::vector<std::string>{"a"}));
  fabatlas::design::Design dn = fabatlas::design::ParseDesign(none.design_yaml, dir / "none.yaml");
  EXPECT_TRUE(dn.exposed.empty());
  ASSERT_EQ(dn.fixed.size(), 1u);
  EXPECT_EQ(dn.fixed[0].value, "1");
}

// A model of 18 Customizer parameters written to the manual's rules
// (tests/scad/data/organiser.scad): the automatic choice under the dimension
// budget, what stays fixed and why, ranges from the command line.
TEST(Import, ManyParametersUnderADimensionBudget) {
  const std::filesystem::path model = fabatlas::testing::SourceDir() / "tests/scad/data/organiser.scad";
  std::ifstream in(model);
  const CustomizerModel m =
      fabatlas::scad::ReadCustomizer(std::string(std::istreambuf_iterator<char>(in), {}), "organiser.scad");
  EXPECT_TRUE(m.warnings.empty());
  ASSERT_EQ(m.parameters.size(), 18u);         // width .. label_text, $fn, eps, tag
  EXPECT_EQ(Find(m, "lip").widget, W::kNone);  // `// .5`: a spin box's step, not a range

  // Default: sliders and dropdowns by group (tab) then file order, up to 6.
  fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(model, {});
  EXPECT_EQ(s.exposed, (std::vector<std::string>{"width", "depth", "height", "columns", "rows", "divider"}));
  ASSERT_EQ(s.decisions.size(), 18u);
  auto decision = [&](const std::string& head) {
    for (const auto& line : s.decisions)
      if (line.rfind(head, 0) == 0) return line;
    return std::string("none for ") + head;
  };
  EXPECT_EQ(decision("exposed width"), "exposed width: slider [40:5:160] in group 'Size', within --max-dims 6");
  EXPECT_EQ(decision("fixed divider_ratio"),
            "fixed divider_ratio = 0.8: beyond --max-dims 6 (slider [0.4:0.05:1] in group 'Compartments')");
  EXPECT_NE(decision("fixed lip = 1.5: no range").find("--expose lip=lo:hi"), std::string::npos);
  EXPECT_EQ(decision("fixed tag"), "fixed tag = 7: in [Hidden]");
  EXPECT_EQ(decision("fixed label_text"), "fixed label_text = \"tools\": a string (text box): not sampled");
  fabatlas::design::Design d = fabatlas::design::ParseDesign(s.design_yaml, model.parent_path() / "organiser.yaml");
  ASSERT_EQ(d.exposed.size(), 6u);
  ASSERT_EQ(d.fixed.size(), 9u);  // every other parameter but $fn and [Hidden]
  EXPECT_EQ(d.fixed[0].name, "divider_ratio");
  const auto lip = std::find_if(d.fixed.begin(), d.fixed.end(), [](const auto& f) { return f.name == "lip"; });
  ASSERT_NE(lip, d.fixed.end());
  EXPECT_EQ(lip->value, "1.5");
  EXPECT_EQ(lip->group, "Finish");
  EXPECT_EQ(lip->description, "Stacking lip height (mm)");
  EXPECT_NE(s.job_yaml.find("cache: {strategy: opt_max}"), std::string::npos) << s.job_yaml;
  EXPECT_NE(s.job_yaml.find("{name: PLA, density: 1.24"), std::string::npos) << s.job_yaml;

  // A larger budget takes the next sliders in order.
  fabatlas::scad::ImportOptions o;
  o.max_dims = 8;
  EXPECT_EQ(
      fabatlas::scad::ImportScad(model, o).exposed,
      (std::vector<std::string>{"width", "depth", "height", "columns", "rows", "divider", "divider_ratio", "wall"}));

  // Ranges: a spin box gets one (real: the model's 1.5 is not whole), a
  // slider's is replaced (integer: whole ends, step and value).
  o = {};
  fabatlas::scad::AddExposeItem("lip=0:3", o);
  fabatlas::scad::AddExposeItem("columns=2:5:1", o);
  fabatlas::scad::AddExposeItem("notches", o);
  s = fabatlas::scad::ImportScad(model, o);
  EXPECT_EQ(s.exposed, (std::vector<std::string>{"columns", "notches", "lip"}));
  d = fabatlas::design::ParseDesign(s.design_yaml, model.parent_path() / "organiser.yaml");
  EXPECT_EQ(d.exposed[0].kind, fabatlas::design::ParameterKind::kInteger);
  EXPECT_EQ(d.exposed[0].min, 2);
  EXPECT_EQ(d.exposed[0].max, 5);
  EXPECT_EQ(d.exposed[2].kind, fabatlas::design::ParameterKind::kReal);
  EXPECT_EQ(d.exposed[2].max, 3);
  EXPECT_EQ(d.exposed[2].default_value, 1.5);
  bool said = false;
  for (const auto& line : s.decisions) said = said || line == "exposed lip: range 0:3 from --expose";
  EXPECT_TRUE(said);
}

// Customizer groups (tabs) are one group however often they reopen: the
// choice takes a group's sliders together, in file order within it.
TEST(Import, GroupsBeforeFileOrder) {
  auto dir = fabatlas::testing::FreshTempDir("scad-import-groups");
  std::ofstream(dir / "g.scad")
      << "/* [A] */\na1 = 1; // [0:2]\n/* [B] */\nb1 = 1; // [0:2]\n/* [A] */\na2 = 1; // [0:2]\ncube(a1 + b1 + a2);\n";
  fabatlas::scad::ImportOptions o;
  o.max_dims = 2;
  fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(dir / "g.scad", o);
  EXPECT_EQ(s.exposed, (std::vector<std::string>{"a1", "a2"}));
  EXPECT_EQ(s.fixed, (std::vector<std::string>{"b1"}));
}

// Bad --expose items and budgets: one line naming the model, the line and what is wrong.
TEST(Import, BadRangesAreOneLine) {
  const std::filesystem::path model = fabatlas::testing::SourceDir() / "tests/scad/data/organiser.scad";
  auto message = [&](std::vector<std::string> items, int max_dims = 6) {
    try {
      fabatlas::scad::ImportOptions o;
      o.max_dims = max_dims;
      for (const auto& item : items) fabatlas::scad::AddExposeItem(item, o);
      fabatlas::scad::ImportScad(model, o);
    } catch (const fabatlas::InputError& e) {
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({"lip=0:x"}),
            "--expose lip=0:x: malformed range '0:x' (expected NAME=lo:hi or NAME=lo:hi:step, numbers)");
  EXPECT_NE(message({"lip=0:3:"}).find("malformed range '0:3:'"), std::string::npos);
  EXPECT_EQ(message({"lip=3:1"}), "--expose lip=3:1: lo 3 is not below hi 1");
  EXPECT_EQ(message({"lip=0:3:0"}), "--expose lip=0:3:0: step 0 must be positive");
  EXPECT_NE(message({"lip=2:3"}).find("organiser.scad:39: --expose lip: the model's value 1.5 lies outside 2:3"),
            std::string::npos);
  EXPECT_NE(message({"label_text=0:1"})
                .find("organiser.scad:43: --expose label_text: the parameter is a string (text box) (\"tools\"), a "
                      "range needs a number"),
            std::string::npos);
  EXPECT_NE(message({"label=0:2"}).find("--expose label: the parameter is a dropdown"), std::string::npos);
  EXPECT_NE(message({"nope=0:2"}).find("--expose nope: the model has no Customizer parameter 'nope'"),
            std::string::npos);
  EXPECT_NE(message({"lip_inset"})
                .find("organiser.scad:41: --expose lip_inset: the parameter has no slider or dropdown annotation"),
            std::string::npos);
  EXPECT_NE(message({"width", "depth", "height"}, 2).find("--expose names 3 parameters, more than --max-dims 2"),
            std::string::npos);
  EXPECT_NE(message({}, 17).find("--max-dims 17 is outside 1..16"), std::string::npos);
}

}  // namespace

#include "fabatlas/scad/region_distance.h"
#include "fabatlas/scad/svg_outline.h"

namespace {

// A 10 mm square with a 4 mm square hole (even-odd): distances by hand.
TEST(ScadRegionDistance, SquareWithHoleIsExact) {
  fabatlas::scad::RegionDistance d({{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {{3, 3}, {7, 3}, {7, 7}, {3, 7}}});
  EXPECT_NEAR(d(5, 5), 2, 1e-12);       // in the hole: 2 mm from its edges
  EXPECT_NEAR(d(1.5, 5), -1.5, 1e-12);  // in the wall: 1.5 mm from the outer edge
  EXPECT_NEAR(d(2.5, 5), -0.5, 1e-12);  // 0.5 mm from the hole
  EXPECT_NEAR(d(-3, -4), 5, 1e-12);     // from the corner (0, 0)
  EXPECT_NEAR(d(20, 5), 10, 1e-12);
  EXPECT_NEAR(d(10, 5), 0, 1e-12);
  // A 1000-gon circle of radius 10: the distance of points inside and far out.
  fabatlas::scad::RegionDistance c({fabatlas::scad::CircleLoop(10, 1000)});
  EXPECT_NEAR(c(0, 0), -10 * std::cos(std::numbers::pi / 1000), 1e-9);
  EXPECT_NEAR(c(30, 40), 40, 1e-3);
  EXPECT_NEAR(c(3, 4), -5, 1e-3);
}

// OpenSCAD 2021.01's SVG export of a 2D shape (y down) read back.
TEST(ScadSvgOutline, ReadsLoopsWithYUp) {
  const std::string svg =
      "<svg><title>OpenSCAD Model</title>\n<path d=\"\nM 0,-0 L 10,-0 L 10,-5 L 0,-5 z\n"
      "M 1,-1 L 2,-1 L 2,-2\n z\n\" stroke=\"black\"/>\n</svg>\n";
  auto loops = fabatlas::scad::ReadSvgOutline(svg, "x.svg");
  ASSERT_EQ(loops.size(), 2u);
  ASSERT_EQ(loops[0].size(), 4u);
  EXPECT_EQ(loops[0][2][0], 10);
  EXPECT_EQ(loops[0][2][1], 5);
  EXPECT_EQ(loops[1].size(), 3u);
  EXPECT_TRUE(fabatlas::scad::ReadSvgOutline("<svg></svg>", "e.svg").empty());
  EXPECT_THROW(fabatlas::scad::ReadSvgOutline("<path d=\"M 0,0 C 1,1 2,2\"/>", "c.svg"), fabatlas::InputError);
}

}  // namespace

#include "fabatlas/scad/csg_tree.h"

namespace {

// The .csg export keeps background ('%') nodes; OpenSCAD does not render
// them, so the tree drops them (Debian's offset.scad draws a % cylinder and
// sphere around its model).
TEST(ScadCsgTree, BackgroundNodesAreDropped) {
  auto root = fabatlas::scad::ParseCsg(
      "%cube(size = [1, 1, 1], center = false);\ncube(size = [2, 2, 2], center = false);\n"
      "union() {\n\t%sphere(r = 1);\n\tcylinder(h = 1, r1 = 1, r2 = 1, center = false);\n}\n",
      "m.csg");
  ASSERT_EQ(root.children.size(), 2u);
  EXPECT_EQ(root.children[0].name, "cube");
  ASSERT_EQ(root.children[0].args.at("size").items.size(), 3u);
  EXPECT_EQ(root.children[0].args.at("size").items[0].number, 2);  // not the % cube
  ASSERT_EQ(root.children[1].children.size(), 1u);
  EXPECT_EQ(root.children[1].children[0].name, "cylinder");
}

// OpenSCAD's lexical rules (User Manual: comments, strings), which the .csg
// parser shares with the Customizer reader: both comment kinds are skipped,
// their lines counted, and escapes in strings applied.
// The Customizer reader and the native evaluator read a model's names with
// one lexer (lex_source.h): OpenSCAD takes `8bit` as a name (`openscad -o
// m.csg -D 8bit=5` on this model writes `cube(size = [5, 5, 5], center =
// false);`), so it is a parameter, and -D reaches it natively too.
TEST(Customizer, NamesAreReadAsTheNativeEvaluatorReadsThem) {
  const std::string model = "8bit = 3; // [1:8]\ncube(8bit);\n";
  const CustomizerModel m = fabatlas::scad::ReadCustomizer(model, "m.scad");
  ASSERT_TRUE(Has(m, "8bit"));
  EXPECT_EQ(Find(m, "8bit").widget, W::kSlider);
  const auto own = fabatlas::scad::EvaluateModelText(model, "m.scad", {{"8bit", "5"}});
  ASSERT_TRUE(own.evaluated) << own.declined;
  EXPECT_NE(own.csg.find("cube(size = [5, 5, 5], center = false);"), std::string::npos) << own.csg;
}

TEST(ScadCsgTree, CommentsAndStringsFollowOpenScadsLexicalRules) {
  auto root = fabatlas::scad::ParseCsg("// exported\n/* two\nlines */ text(text = \"a\\\"b\\n\");\n\ncube(size = 1);\n",
                                       "m.csg");
  ASSERT_EQ(root.children.size(), 2u);
  EXPECT_EQ(root.children[0].line, 3);
  EXPECT_EQ(root.children[0].args.at("text").text, "a\"b\n");
  EXPECT_EQ(root.children[1].line, 5);
  // An unterminated block comment runs to the end of the text; an
  // unterminated string is an error at the line the text ends on.
  EXPECT_EQ(fabatlas::scad::ParseCsg("cube(size = 1);\n/* cube(size = 2);\n", "m.csg").children.size(), 1u);
  try {
    fabatlas::scad::ParseCsg("cube(size = 1);\ntext(text = \"x\n", "m.csg");
    ADD_FAILURE() << "an unterminated string was accepted";
  } catch (const fabatlas::InputError& e) {
    EXPECT_STREQ(e.what(), "m.csg:3: unterminated string");
  }
}

}  // namespace

#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/csg_bounds.h"
#include "fabatlas/scad/model_bounds.h"

namespace {

using fabatlas::scad::CsgBounds;
using fabatlas::scad::ParseCsg;

std::array<double, 6> Box(const std::string& csg) {
  const fabatlas::scad::CsgBox b = CsgBounds(ParseCsg(csg, "m.csg"));
  EXPECT_TRUE(b.known) << b.unknown;
  EXPECT_FALSE(b.empty);
  return {b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]};
}

// Boxes read from the CSG tree without booleans (csg_bounds.h), against
// boxes worked out by hand from the primitives' definitions (OpenSCAD User
// Manual: cube, cylinder, linear_extrude, multmatrix).
TEST(ScadCsgBounds, BoxesOfPrimitivesTransformsAndBooleans) {
  using B = std::array<double, 6>;
  const std::string moved =
      "multmatrix([[1, 0, 0, 10], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n"
      "cube(size = [2, 3, 4], center = false);\n}\n";
  // A union: the boxes' union, a centred cube with a moved one.
  EXPECT_EQ(Box(moved + "cube(size = [5, 5, 5], center = true);\n"), (B{-2.5, -2.5, -2.5, 12, 3, 4}));
  // A difference: its first operand's box, whatever it cuts away.
  EXPECT_EQ(Box("difference() {\n" + moved + "sphere($fn = 0, $fa = 12, $fs = 2, r = 100);\n}\n"),
            (B{10, 0, 0, 12, 3, 4}));
  // An intersection: the overlap; of disjoint boxes, nothing.
  EXPECT_EQ(Box("intersection() {\ncube(size = [11, 11, 11], center = false);\n" + moved + "}\n"),
            (B{10, 0, 0, 11, 3, 4}));
  EXPECT_TRUE(
      CsgBounds(ParseCsg("intersection() {\ncube(size = [1, 1, 1], center = false);\n" + moved + "}\n", "m.csg"))
          .empty);
  // A quarter turn about z: (x, y) -> (-y, x).
  EXPECT_EQ(Box("multmatrix([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n"
                "cube(size = [2, 3, 4], center = false);\n}\n"),
            (B{-3, 0, 0, 0, 2, 4}));
  // A cone and a centred extrusion of a polygon; 2-D shapes alone are no solid.
  EXPECT_EQ(Box("cylinder($fn = 0, $fa = 12, $fs = 2, h = 6, r1 = 1, r2 = 3, center = false);\n"),
            (B{-3, -3, 0, 3, 3, 6}));
  EXPECT_EQ(Box("linear_extrude(height = 4, center = true, convexity = 1, scale = [1, 1]) {\n"
                "polygon(points = [[0, 0], [5, 1], [2, 7]], paths = undef, convexity = 1);\n}\n"),
            (B{0, 0, -2, 5, 7, 2}));
  EXPECT_TRUE(CsgBounds(ParseCsg("square(size = [2, 2], center = false);\n", "m.csg")).empty);
  // Text's extent is not in its arguments: unknown, naming the line.
  const fabatlas::scad::CsgBox text = CsgBounds(ParseCsg(
      "cube(size = [1, 1, 1], center = false);\nlinear_extrude(height = 1) {\ntext(text = \"A\", size = 10);\n}\n",
      "m.csg"));
  EXPECT_FALSE(text.known);
  EXPECT_EQ(text.unknown, "3: text");
}

// A model nobody on the team wrote (MCAD's trochoids demo: cylinders, a
// twisted extrusion, polygons from functions, colours): the box from its CSG
// tree holds OpenSCAD 2021.01's own STL and is at most 10% longer on its
// largest edge (the twisted extrusion is bounded by the circle it sweeps:
// 24.9 mm against OpenSCAD's 23.2 mm).
TEST(ScadCsgBounds, HoldsOpenScadsRenderOfAnMcadModel) {
  const std::filesystem::path model = "/usr/share/openscad/libraries/MCAD/trochoids.scad";
  if (!std::filesystem::exists(model) || std::system("openscad --version >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "openscad or openscad-mcad not installed";
  const auto dir = fabatlas::testing::FreshTempDir("scad-bounds");
  const std::string stl = (dir / "t.stl").string();
  ASSERT_EQ(std::system(("openscad --quiet -o " + stl + " " + model.string() + " 2>/dev/null").c_str()), 0);
  const fabatlas::mesh::TriangleMesh mesh = fabatlas::mesh::ReadMesh(stl);
  ASSERT_FALSE(mesh.vertices.empty());
  std::array<double, 3> lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const auto& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
  const fabatlas::scad::CsgBox b = fabatlas::scad::ModelBounds(model);
  ASSERT_TRUE(b.known) << b.unknown;
  double theirs = 0, ours = 0;
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(b.lo[k], lo[k] + 1e-3) << k;
    EXPECT_GE(b.hi[k], hi[k] - 1e-3) << k;
    theirs = std::max(theirs, hi[k] - lo[k]);
    ours = std::max(ours, b.hi[k] - b.lo[k]);
  }
  EXPECT_LE(ours, 1.1 * theirs) << ours << " mm against OpenSCAD's " << theirs << " mm";
}

}  // namespace

namespace {

// Debian's openscad-mcad, imported without options: no part has a
// Customizer annotation, so each imports as a one-sample design whose
// numbers are fixed at the library's values (trochoids.scad's as written in
// it), and the design file parses.
TEST(Import, McadPartsWithoutOptionsAreOneSampleDesigns) {
  const std::filesystem::path dir = "/usr/share/openscad/libraries/MCAD";
  if (!std::filesystem::exists(dir / "stepper.scad")) GTEST_SKIP() << "openscad-mcad not installed";
  int models = 0, with_numbers = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".scad") continue;
    const fabatlas::scad::ImportSummary s = fabatlas::scad::ImportScad(entry.path(), {});
    EXPECT_TRUE(s.exposed.empty()) << entry.path();
    const fabatlas::design::Design d =
        fabatlas::design::ParseDesign(s.design_yaml, entry.path().parent_path() / "imported.yaml");
    EXPECT_TRUE(d.exposed.empty()) << entry.path();
    ++models;
    with_numbers += !d.fixed.empty();
  }
  EXPECT_GE(models, 30);
  EXPECT_GE(with_numbers, 8);  // bearing, hardware, lego_compatibility, stepper, trochoids, units, ...
  const fabatlas::scad::ImportSummary trochoids = fabatlas::scad::ImportScad(dir / "trochoids.scad", {});
  const fabatlas::design::Design d = fabatlas::design::ParseDesign(trochoids.design_yaml, dir / "trochoids.yaml");
  std::map<std::string, std::string> fixed;
  for (const auto& f : d.fixed) fixed[f.name] = f.value;
  EXPECT_EQ(fixed,
            (std::map<std::string, std::string>{{"thickness", "2"}, {"R", "4"}, {"r", "1"}, {"d", "1"}, {"n", "60"}}));
  // ($fn = 30 is a $-variable, not listed; alpha = 360 * $t an expression.)
}

}  // namespace
