// The pure parts of the benchmarks' shared helpers: orders of convergence,
// Pareto fronts, splicing into a Markdown page, CSV and Markdown output, and
// that the SVG writer produces a well-formed picture with what it promises.
#include "bench/common/bench_common.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace alloy::bench {
namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("alloy-bench-common-test-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

TEST(LoglogSlope, PowerLawGivesItsExponent) {
  std::vector<double> x, y;
  for (double h : {1e-3, 2e-3, 4e-3, 8e-3, 1.6e-2}) x.push_back(h), y.push_back(3.7 * h * h);
  EXPECT_NEAR(loglog_slope(x, y), 2.0, 1e-12);
  // Order 1 with a constant in front, and decreasing x: the sign is right.
  std::vector<double> y1;
  for (double h : x) y1.push_back(0.2 * h);
  EXPECT_NEAR(loglog_slope(x, y1), 1.0, 1e-12);
}

TEST(LoglogSlope, IgnoresNonPositiveAndNonFinite) {
  const std::vector<double> x = {1, 2, 4, 8, 16};
  const std::vector<double> y = {1, 0, 16, NAN, 256};  // y = x^2 where usable
  EXPECT_NEAR(loglog_slope(x, y), 2.0, 1e-12);
  EXPECT_TRUE(std::isnan(loglog_slope({1, 2}, {1, 0})));
  EXPECT_TRUE(std::isnan(loglog_slope({}, {})));
}

TEST(ParetoFront, KeepsOnlyUndominatedSortedByCost) {
  //                         0    1    2    3    4    5
  const std::vector<double> cost = {3.0, 1.0, 2.0, 2.5, 4.0, 1.0};
  const std::vector<double> err = {0.1, 1.0, 0.5, 0.6, 0.05, 2.0};
  // 3 is dominated by 2 (cheaper and better), 5 by 1 (same cost, worse).
  EXPECT_EQ(pareto_front(cost, err), (std::vector<std::size_t>{1, 2, 0, 4}));
}

TEST(ParetoFront, SkipsNonFinite) {
  const std::vector<double> cost = {1.0, 2.0, NAN};
  const std::vector<double> err = {INFINITY, 1.0, 0.0};
  EXPECT_EQ(pareto_front(cost, err), (std::vector<std::size_t>{1}));
}

TEST(Splice, ReplacesBetweenMarkersAndKeepsTheRest) {
  const fs::path doc = scratch("splice_replace.md");
  std::ofstream(doc) << "# Title\n\nprose before\n<!-- bench:wp -->\nold table\n"
                        "<!-- /bench:wp -->\nprose after\n<!-- bench:other -->\nx\n"
                        "<!-- /bench:other -->\n";
  splice(doc, "wp", "| a |\n|---|\n| 1 |\n");
  EXPECT_EQ(read(doc),
            "# Title\n\nprose before\n<!-- bench:wp -->\n| a |\n|---|\n| 1 |\n"
            "<!-- /bench:wp -->\nprose after\n<!-- bench:other -->\nx\n<!-- /bench:other -->\n");
  // Twice gives the same page: nothing accumulates between runs.
  splice(doc, "wp", "| a |\n|---|\n| 1 |");
  EXPECT_NE(read(doc).find("<!-- bench:wp -->\n| a |\n|---|\n| 1 |\n<!-- /bench:wp -->"),
            std::string::npos);
  EXPECT_EQ(read(doc).find("old table"), std::string::npos);
}

TEST(Splice, AppendsWhenMarkersAreMissing) {
  const fs::path doc = scratch("splice_append.md");
  std::ofstream(doc) << "# Title\nno markers";
  splice(doc, "new", "content");
  EXPECT_EQ(read(doc), "# Title\nno markers\n\n<!-- bench:new -->\ncontent\n<!-- /bench:new -->\n");
  splice(doc, "new", "second");
  EXPECT_EQ(read(doc), "# Title\nno markers\n\n<!-- bench:new -->\nsecond\n<!-- /bench:new -->\n");
}

TEST(Splice, EmptyPathIsANoOp) {
  EXPECT_NO_THROW(splice("", "k", "x"));
}

TEST(Csv, HeaderRowsQuotingAndNumbers) {
  const fs::path p = scratch("out.csv");
  {
    Csv csv(p, {"scene", "dt", "error"});
    csv.row({"free fall", Csv::cell(1.0 / 240), Csv::cell(1.5e-7)});
    csv.row({"a,b", Csv::cell(3), Csv::cell(NAN)});
    csv.row({"short"});
  }
  EXPECT_EQ(read(p), "scene,dt,error\nfree fall,0.00416666667,1.5e-07\n\"a,b\",3,nan\nshort,,\n");
}

TEST(Fmt, SignificantDigits) {
  EXPECT_EQ(fmt(0.0421), "0.0421");
  EXPECT_EQ(fmt(3.0), "3.00");
  EXPECT_EQ(fmt(1.2e-5, 2), "1.2e-05");
  EXPECT_EQ(fmt(123456.0), "1.23e+05");
  EXPECT_EQ(fmt(100.0), "100");
}

TEST(Table, Markdown) {
  Table t({"method", "order"});
  t.row({"quick 40", "1.00"});
  t.row({"a|b"});
  EXPECT_EQ(t.str(), "| method | order |\n|---|---|\n| quick 40 | 1.00 |\n| a\\|b |  |\n");
}

TEST(Svg, WellFormedWithSeriesLegendAndMarker) {
  Plot plot;
  plot.title = "free fall <test>";
  plot.x_label = "run time per simulated second (s)";
  plot.y_label = "error (m)";
  plot.series.push_back({"step", {1e-3, 2e-3, 4e-3}, {1e-2, 5e-3, 2.5e-3}});
  plot.series.push_back({"quick 40", {1e-3, 2e-3, -1.0}, {2e-2, NAN, 1e-3}});
  plot.markers.push_back({2e-3, 5e-3, "default"});
  const fs::path p = scratch("plot.svg");
  write_svg(plot, p);
  const std::string s = read(p);
  EXPECT_EQ(s.rfind("<svg", 0), 0u);
  EXPECT_NE(s.find("</svg>"), std::string::npos);
  EXPECT_NE(s.find("free fall &lt;test&gt;"), std::string::npos);  // escaped
  EXPECT_NE(s.find(">step<"), std::string::npos);
  EXPECT_NE(s.find(">quick 40<"), std::string::npos);
  EXPECT_NE(s.find(">default<"), std::string::npos);
  EXPECT_NE(s.find("run time per simulated second (s)"), std::string::npos);
  // Decade labels on both log axes (10^-3 on x, 10^-2 on y).
  EXPECT_NE(s.find("10<tspan dy=\"-6\" font-size=\"10\">-3</tspan>"), std::string::npos);
  EXPECT_NE(s.find("10<tspan dy=\"-6\" font-size=\"10\">-2</tspan>"), std::string::npos);
  EXPECT_EQ(s.find("nan"), std::string::npos);  // skipped points leave no trace
  EXPECT_EQ(s.find("inf"), std::string::npos);
}

}  // namespace
}  // namespace alloy::bench
