// What every benchmark program shares: its command line, CPU timing, a
// progress bar on stderr, CSV output, log-log SVG plots, least-squares orders
// of convergence, Pareto fronts, Markdown tables, and splicing a generated
// section into docs/performance.md between markers.
//
// Conventions (README "Benchmarks", docs/performance.md):
//   prog [--quick] [--out DIR] [--docs FILE] [--no-progress]
//     --quick        a small sweep that finishes in seconds (CI runs it as a
//                    test, so the program cannot rot); writes no docs
//     --out DIR      where CSV and SVG files go (default: docs/bench)
//     --docs FILE    the Markdown page to splice tables into
//                    (default: docs/performance.md; never in --quick)
//   Exit code 0 when the run finished, 1 when a goal it checks was missed
//   (the program still writes everything), 2 on bad arguments.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace alloy::bench {

struct Options {
  bool quick = false;
  bool progress = true;
  std::filesystem::path out = "docs/bench";
  std::filesystem::path docs = "docs/performance.md";  ///< empty: do not splice
  /// Parses the conventions above; prints usage and exits 2 on bad arguments.
  /// `extra` lists further flags the program accepts (e.g. "--full"); their
  /// presence is reported by flag().
  static Options parse(int argc, char** argv, std::string_view program,
                       std::vector<std::string> extra = {});
  bool flag(std::string_view name) const;
  /// out / file name, creating `out` if needed.
  std::filesystem::path file(std::string_view name) const;

  std::vector<std::string> flags_set;
};

/// CPU time of this process, in seconds (immune to other work on the machine
/// as long as it does not steal this process's core).
double cpu_seconds();

/// Times `fn` in CPU seconds.
template <class F>
double cpu_time(F&& fn) {
  const double t0 = cpu_seconds();
  fn();
  return cpu_seconds() - t0;
}

/// A progress bar on stderr: "label [#####.....] 12/40  0:31 left".
/// Redraws in place on a terminal, prints every 10 % otherwise; silent when
/// disabled.
class Progress {
 public:
  Progress(std::string label, std::size_t total, bool enabled = true);
  ~Progress();
  void tick(std::size_t n = 1);
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

 private:
  void draw(bool final);
  std::string label_;
  std::size_t total_, done_ = 0;
  bool enabled_, tty_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point start_;
};

/// A CSV file with a header row; values are written with 9 significant digits.
class Csv {
 public:
  Csv(const std::filesystem::path& path, std::vector<std::string> columns);
  ~Csv();
  /// One row; a cell is a string or a number (use cell()).
  void row(const std::vector<std::string>& cells);
  static std::string cell(double v);
  static std::string cell(long long v) { return std::to_string(v); }
  static std::string cell(int v) { return std::to_string(v); }
  static std::string cell(std::string v) { return v; }
  static std::string cell(const char* v) { return v; }
  Csv(const Csv&) = delete;
  Csv& operator=(const Csv&) = delete;

 private:
  std::FILE* f_;
  std::size_t columns_;
};

/// "%.3g"-style number for tables ("1.2e-05", "0.0421", "3.00").
std::string fmt(double v, int significant = 3);

/// A Markdown table.
class Table {
 public:
  explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}
  void row(std::vector<std::string> cells) { rows_.push_back(std::move(cells)); }
  std::string str() const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

/// One line of a plot: points joined in the order given.
struct Series {
  std::string name;
  std::vector<double> x, y;
  bool line = true;      ///< join the points; false: markers only
  bool dashed = false;
};

/// A point to mark and label (e.g. "default").
struct Marker {
  double x = 0, y = 0;
  std::string label;
};

struct Plot {
  std::string title;
  std::string x_label;  ///< with units, e.g. "run time per simulated second (s)"
  std::string y_label;  ///< with units, e.g. "max position error (m)"
  bool log_x = true, log_y = true;
  std::vector<Series> series;
  std::vector<Marker> markers;
};

/// Writes an SVG (about 800 x 560 px): axes with decade ticks and labels on log
/// scales, a grid, one colour and point shape per series, a legend, markers
/// drawn as rings with their labels. Non-positive values on a log axis and
/// non-finite values are skipped.
void write_svg(const Plot& plot, const std::filesystem::path& path);

/// Least-squares slope of log(y) against log(x): the observed order of
/// convergence when x is the step and y the error (points with y <= 0 or
/// non-finite are ignored; NaN if fewer than two remain).
double loglog_slope(const std::vector<double>& x, const std::vector<double>& y);

/// Indices of the points on the Pareto front of (cost, error), both to be
/// minimised: no other point is at least as good in both and better in one.
/// Sorted by increasing cost.
std::vector<std::size_t> pareto_front(const std::vector<double>& cost,
                                      const std::vector<double>& error);

/// Replaces the text between "<!-- bench:KEY -->" and "<!-- /bench:KEY -->"
/// in `doc` with `content` (the markers stay). Appends the marked section at
/// the end if the markers are missing. No-op if `doc` is empty.
void splice(const std::filesystem::path& doc, std::string_view key, std::string_view content);

}  // namespace alloy::bench
