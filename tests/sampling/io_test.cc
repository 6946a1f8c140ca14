// Job file parsing, form JSON round trip, validity-map PNG.
#include <png.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "analytic_designs.h"
#include "fabatlas/error.h"
#include "fabatlas/sampling/form_json.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/sampling/point_key_text.h"
#include "fabatlas/sampling/validity_map.h"

namespace fabatlas::sampling {
namespace {

std::string ErrorOf(const std::string& yaml) {
  try {
    ParseJobFile(yaml, "jobs/vase.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(SamplingJobFile, ParsesAllSections) {
  const JobFile job = ParseJobFile(
      "design: ../designs/vase.yaml\n"
      "sampling:\n"
      "  subdivisions: 7\n"
      "  max_depth: 9\n"
      "  dg_threshold: 0.05\n"
      "  max_samples: 20000\n"
      "threads: 2\n"
      "cluster: {workers: 4}\n",
      "configs/jobs/vase.yaml");
  EXPECT_EQ(job.design_path, "configs/designs/vase.yaml");
  EXPECT_EQ(job.subdivisions, 7);
  EXPECT_EQ(job.sampling.max_depth, 9);
  EXPECT_DOUBLE_EQ(job.sampling.dg_threshold, 0.05);
  EXPECT_EQ(job.sampling.max_samples, 20000);
  EXPECT_EQ(job.threads, 2);
  ASSERT_EQ(job.reserved_sections.count("cluster"), 1u);
  EXPECT_NE(job.reserved_sections.at("cluster").find("workers"), std::string::npos);
  // Defaults.
  const JobFile minimal = ParseJobFile("design: /abs/cup.yaml\n", "job.yaml");
  EXPECT_EQ(minimal.design_path, "/abs/cup.yaml");
  EXPECT_EQ(minimal.subdivisions, 5);
  EXPECT_EQ(minimal.sampling.max_depth, SamplingOptions{}.max_depth);
  EXPECT_EQ(minimal.threads, 1);
  EXPECT_DOUBLE_EQ(minimal.cache_min_subtree_seconds, 0.1);
  const JobFile cached = ParseJobFile("design: a.yaml\ncache: {min_subtree_seconds: 0.25}\n", "job.yaml");
  EXPECT_DOUBLE_EQ(cached.cache_min_subtree_seconds, 0.25);
  EXPECT_EQ(cached.reserved_sections.count("cache"), 1u);
}

TEST(SamplingJobFile, ErrorsNameFileLineAndColumn) {
  EXPECT_EQ(ErrorOf("design: a.yaml\nsampling:\n  max_depht: 3\n"),
            "jobs/vase.yaml:3:3: unknown key 'sampling.max_depht' (expected subdivisions, max_depth, "
            "dg_threshold, max_samples)");
  EXPECT_EQ(ErrorOf("design: a.yaml\nsampling:\n  dg_threshold: 1.5\n"),
            "jobs/vase.yaml:3:17: sampling.dg_threshold must be in [0.000000, 1.000000], got 1.5");
  EXPECT_EQ(ErrorOf("design: a.yaml\nthreads: two\n"), "jobs/vase.yaml:2:10: threads must be an integer, got 'two'");
  EXPECT_EQ(ErrorOf("sampling: {max_depth: 3}\n"), "jobs/vase.yaml:1:1: missing required key 'design'");
  EXPECT_EQ(ErrorOf("design: a.yaml\ncache:\n  min_subtree_seconds: -1\n"),
            "jobs/vase.yaml:3:24: cache.min_subtree_seconds must be in [0.000000, 1000000000.000000], got -1");
  EXPECT_EQ(
      ErrorOf("design: a.yaml\nwhatever: 1\n"),
      "jobs/vase.yaml:2:1: unknown key 'whatever' (expected design, sampling, threads, materials, cluster, cache)");
  const std::string syntax = ErrorOf("design: [a.yaml\n");
  EXPECT_EQ(syntax.rfind("jobs/vase.yaml:", 0), 0u) << syntax;
  EXPECT_EQ(syntax.find('\n'), std::string::npos);
  EXPECT_THROW(ReadJobFile("/nonexistent/job.yaml"), InputError);
}

SamplingSummary SampleCylinder(int depth) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(2);
  SamplingOptions o;
  o.max_depth = depth;
  o.dg_threshold = 0.3;
  return SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o);
}

TEST(SamplingFormJson, RoundTripIsByteIdentical) {
  const auto s = SampleCylinder(5);
  const std::string text = FormToJson(s.form);
  const Form back = FormFromJson(text);
  EXPECT_EQ(FormToJson(back), text);
  EXPECT_EQ(back.samples.size(), s.form.samples.size());
  EXPECT_EQ(back.geometry_changes, s.form.geometry_changes);
  EXPECT_DOUBLE_EQ(ValidVolumePercent(back), s.statistics.valid_volume_percent);
  EXPECT_NE(FormToJson(s.form, true).find("cpu_seconds"), std::string::npos);
  EXPECT_EQ(text.find("cpu_seconds"), std::string::npos);
}

TEST(SamplingFormJson, RejectsBrokenForms) {
  const std::string text = FormToJson(SampleCylinder(2).form);
  auto error = [](const std::string& t) {
    try {
      FormFromJson(t, "cyl.form.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error("{").rfind("cyl.form.json: ", 0), 0u);
  std::string wrong = text;
  wrong.replace(wrong.find("fabatlas.form/1"), 15, "fabatlas.form/9");
  EXPECT_NE(error(wrong).find("unsupported format"), std::string::npos);
}

struct Png {
  int w = 0, h = 0;
  std::vector<unsigned char> rgb;
  unsigned At(int x, int y) const {
    const unsigned char* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
    return (unsigned(p[0]) << 16) | (unsigned(p[1]) << 8) | p[2];
  }
};

Png ReadPng(const std::string& path) {
  Png img;
  png_image im{};
  im.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&im, path.c_str())) return img;
  im.format = PNG_FORMAT_RGB;
  img.rgb.resize(PNG_IMAGE_SIZE(im));
  if (png_image_finish_read(&im, nullptr, img.rgb.data(), 0, nullptr)) {
    img.w = static_cast<int>(im.width);
    img.h = static_cast<int>(im.height);
  }
  return img;
}

TEST(SamplingValidityMap, PixelsShowValidAndFailureRegions) {
  const auto s = SampleCylinder(6);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("sampling_validity_map_" + std::to_string(::getpid()) + ".png"))
          .string();
  ValidityMapOptions opt;
  const ValidityMapLayout layout = WriteValidityMap(s.form, opt, path);
  const Png img = ReadPng(path);
  ASSERT_EQ(img.w, layout.width);
  ASSERT_EQ(img.h, layout.height);
  EXPECT_GT(layout.width, layout.plot_size);
  auto pixel_at = [&](double R, double t) {
    const int px = layout.plot_left + static_cast<int>((R - 5.0) / 15.0 * layout.plot_size);
    const int py = layout.plot_top + static_cast<int>((5.0 - t) / 4.5 * layout.plot_size);
    return img.At(px, py);
  };
  // Deep inside the valid region (t_min(6.3) = 0.9) and deep inside the
  // min_thickness failure (t_min(18.7) = 4.0), away from leaf borders.
  EXPECT_EQ(pixel_at(6.3, 4.3), ValidColour());
  EXPECT_EQ(pixel_at(18.7, 1.3), FailureColour(s.form, "min_thickness"));
  EXPECT_NE(ValidColour(), FailureColour(s.form, "min_thickness"));
  std::filesystem::remove(path);
  EXPECT_THROW(WriteValidityMap(s.form, ValidityMapOptions{0, 0, {}, 100}, path), InputError);
}

// Keys as text: decimal integers between commas, and only those read back.
TEST(PointKeyText, RoundTripsAndRejectsWhatItDoesNotWrite) {
  const std::vector<std::int64_t> key = {3, 0, -2, INT64_MIN, INT64_MAX};
  EXPECT_EQ(PointKeyText({3, 0, -2}), "3,0,-2");
  EXPECT_EQ(PointKeyText({}), "");
  EXPECT_EQ(ParsePointKeyText(PointKeyText(key)), key);
  ASSERT_TRUE(ParsePointKeyText(""));
  EXPECT_TRUE(ParsePointKeyText("")->empty());
  for (const char* bad : {"3,,2", "3,", ",3", "3,x", "1.5", "3 ", "99999999999999999999"})
    EXPECT_FALSE(ParsePointKeyText(bad)) << bad;
}

}  // namespace
}  // namespace fabatlas::sampling
