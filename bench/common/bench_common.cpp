// What every benchmark program shares (see bench_common.hpp): command line,
// CPU timing, progress bar, CSV, Markdown tables, the project's own log-log
// SVG writer, orders of convergence, Pareto fronts and splicing generated
// sections into docs/performance.md.
#include "bench/common/bench_common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace alloy::bench {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Options

namespace {

[[noreturn]] void usage(std::string_view program, const std::vector<std::string>& extra,
                        const std::string& error) {
  if (!error.empty())
    std::fprintf(stderr, "%.*s: %s\n", int(program.size()), program.data(), error.c_str());
  std::fprintf(stderr, "usage: %.*s [--quick] [--out DIR] [--docs FILE] [--no-progress]",
               int(program.size()), program.data());
  for (const auto& e : extra) std::fprintf(stderr, " [%s]", e.c_str());
  std::fprintf(stderr, "\n");
  std::exit(2);
}

// The defaults name paths in the source tree; resolving them against the
// project root (compiled in) lets a benchmark run from any directory, e.g.
// the build dir, and still regenerate the committed docs.
fs::path in_source_tree(const fs::path& p) {
#ifdef ALLOY_SOURCE_DIR
  if (p.is_relative()) return fs::path(ALLOY_SOURCE_DIR) / p;
#endif
  return p;
}

}  // namespace

Options Options::parse(int argc, char** argv, std::string_view program,
                       std::vector<std::string> extra) {
  Options o;
  bool out_given = false, docs_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--quick") {
      o.quick = true;
    } else if (a == "--no-progress") {
      o.progress = false;
    } else if (a == "--out" || a == "--docs") {
      if (i + 1 >= argc) usage(program, extra, std::string(a) + " needs a value");
      (a == "--out" ? o.out : o.docs) = argv[++i];
      (a == "--out" ? out_given : docs_given) = true;
    } else if (a == "--help" || a == "-h") {
      usage(program, extra, "");
    } else if (std::find(extra.begin(), extra.end(), a) != extra.end()) {
      o.flags_set.emplace_back(a);
    } else {
      usage(program, extra, "unknown argument '" + std::string(a) + "'");
    }
  }
  // --quick never touches the committed docs: without --out it writes to a
  // scratch dir, and it never splices.
  if (o.quick) {
    o.docs.clear();
    if (!out_given) o.out = fs::temp_directory_path() / "alloy-bench-quick";
  } else {
    if (!out_given) o.out = in_source_tree(o.out);
    if (!docs_given) o.docs = in_source_tree(o.docs);
  }
  return o;
}

bool Options::flag(std::string_view name) const {
  return std::find(flags_set.begin(), flags_set.end(), name) != flags_set.end();
}

fs::path Options::file(std::string_view name) const {
  fs::create_directories(out);
  return out / fs::path(name);
}

// ---------------------------------------------------------------------------
// Timing and progress

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

Progress::Progress(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)),
      total_(total),
      enabled_(enabled),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()) {
  if (enabled_) draw(false);
}

Progress::~Progress() {
  if (enabled_) draw(true);
}

void Progress::tick(std::size_t n) {
  done_ = std::min(total_, done_ + n);
  if (enabled_) draw(false);
}

void Progress::draw(bool final) {
  const double frac = total_ ? double(done_) / double(total_) : 1.0;
  const int decile = int(frac * 10.0 + 1e-9);
  // Off a terminal (make's log, CI) a line per tenth is enough.
  if (!tty_ && !final && decile == last_decile_) return;
  if (!tty_ && final && last_decile_ == 10) return;
  last_decile_ = decile;

  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  constexpr int kWidth = 30;
  const int filled = int(frac * kWidth + 1e-9);
  std::string bar(std::size_t(filled), '#');
  bar.append(std::size_t(kWidth - filled), '.');
  char when[48];
  if (final || done_ == total_) {
    std::snprintf(when, sizeof when, "%d:%02d total", int(elapsed) / 60, int(elapsed) % 60);
  } else if (done_ == 0) {
    std::snprintf(when, sizeof when, "  ?:?? left");
  } else {
    const double left = elapsed / frac - elapsed;
    std::snprintf(when, sizeof when, "%d:%02d left", int(left) / 60, int(left) % 60);
  }
  std::fprintf(stderr, "%s%s [%s] %zu/%zu  %s%s", tty_ ? "\r" : "", label_.c_str(), bar.c_str(),
               done_, total_, when, tty_ ? "\033[K" : "\n");
  if (tty_ && final) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

// ---------------------------------------------------------------------------
// CSV and Markdown

namespace {

std::string csv_quote(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"') q += '"';
    q += c;
  }
  return q + "\"";
}

}  // namespace

Csv::Csv(const fs::path& path, std::vector<std::string> columns) : columns_(columns.size()) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  f_ = std::fopen(path.c_str(), "w");
  if (!f_) throw std::runtime_error("cannot write " + path.string());
  row(columns);
}

Csv::~Csv() {
  if (f_) std::fclose(f_);
}

void Csv::row(const std::vector<std::string>& cells) {
  // A short row is padded so that every line has the header's column count.
  for (std::size_t i = 0; i < std::max(columns_, cells.size()); ++i) {
    if (i) std::fputc(',', f_);
    if (i < cells.size()) std::fputs(csv_quote(cells[i]).c_str(), f_);
  }
  std::fputc('\n', f_);
}

std::string Csv::cell(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::string fmt(double v, int significant) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[48];
  // '#' keeps trailing zeros ("3.00"), so every entry shows its precision;
  // a bare trailing point ("100.") is dropped.
  std::snprintf(buf, sizeof buf, "%#.*g", std::max(1, significant), v);
  std::string s = buf;
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

std::string Table::str() const {
  const std::size_t n = header_.size();
  auto line = [n](const std::vector<std::string>& cells) {
    std::string s = "|";
    for (std::size_t i = 0; i < n; ++i) {
      std::string c = i < cells.size() ? cells[i] : "";
      for (std::size_t p = 0; (p = c.find('|', p)) != std::string::npos; p += 2) c.insert(p, "\\");
      s += " " + c + " |";
    }
    return s + "\n";
  };
  std::string s = line(header_) + "|";
  for (std::size_t i = 0; i < n; ++i) s += "---|";
  s += "\n";
  for (const auto& r : rows_) s += line(r);
  return s;
}

// ---------------------------------------------------------------------------
// SVG plots

namespace {

constexpr double kW = 800, kH = 560;
constexpr double kLeft = 92, kRight = 24, kTop = 48, kBottom = 68;

// Distinct on screen and in grey print: colour and shape both change per series.
constexpr const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                    "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"};
constexpr int kShapes = 8;

std::string esc(std::string_view s) {
  std::string r;
  for (char c : s) {
    switch (c) {
      case '&':
        r += "&amp;";
        break;
      case '<':
        r += "&lt;";
        break;
      case '>':
        r += "&gt;";
        break;
      case '"':
        r += "&quot;";
        break;
      default:
        r += c;
    }
  }
  return r;
}

std::string num(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

// One axis: data range mapped to pixels, in log10 units on a log axis.
struct Axis {
  bool log = true;
  double lo = 0, hi = 1;  // in axis units (log10 on a log axis)
  double p0 = 0, p1 = 1;  // pixels of lo and hi

  double to_unit(double v) const { return log ? std::log10(v) : v; }
  bool usable(double v) const { return std::isfinite(v) && (!log || v > 0); }
  double px(double v) const { return p0 + (to_unit(v) - lo) / (hi - lo) * (p1 - p0); }
};

void fit_axis(Axis& a, const std::vector<double>& values) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : values) {
    if (!a.usable(v)) continue;
    lo = std::min(lo, a.to_unit(v));
    hi = std::max(hi, a.to_unit(v));
  }
  if (!std::isfinite(lo)) lo = 0, hi = 1;
  if (hi - lo < 1e-9) {
    const double h = a.log ? 0.5 : std::max(std::abs(lo) * 0.1, 0.5);
    lo -= h, hi += h;
  }
  const double pad = 0.05 * (hi - lo);
  a.lo = lo - pad;
  a.hi = hi + pad;
}

struct Tick {
  double value;  // in data units
  std::string label;
  bool major;
};

// "10^k" label parts: the base and the exponent, drawn as a superscript.
std::string decade_label(int k) {
  return "10<tspan dy=\"-6\" font-size=\"10\">" + std::to_string(k) + "</tspan>";
}

std::string plain_label(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

// Ticks at 1, 2 or 5 times a power of ten between lo and hi (data units),
// a minor tick halfway between.
std::vector<Tick> linear_ticks(double lo, double hi) {
  std::vector<Tick> t;
  const double range = hi - lo;
  const double raw = range / 6;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * mag;
  for (double f : {1.0, 2.0, 5.0})
    if (f * mag >= raw) {
      step = f * mag;
      break;
    }
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-12 * range; v += step) {
    const double z = std::abs(v) < 1e-9 * step ? 0.0 : v;
    t.push_back({z, plain_label(z), true});
    if (z + step / 2 <= hi) t.push_back({z + step / 2, "", false});
  }
  return t;
}

std::vector<Tick> ticks(const Axis& a) {
  if (!a.log) return linear_ticks(a.lo, a.hi);
  // Less than about half a decade on show: decades would leave the axis
  // bare, so plain numbers are placed on the log scale instead.
  if (a.hi - a.lo < 0.6) return linear_ticks(std::pow(10.0, a.lo), std::pow(10.0, a.hi));
  std::vector<Tick> t;
  const int k0 = int(std::floor(a.lo)), k1 = int(std::ceil(a.hi));
  // Label every decade up to a dozen of them, then every other one.
  const int every = k1 - k0 > 12 ? 2 : 1;
  for (int k = k0; k <= k1; ++k) {
    const double d = std::pow(10.0, k);
    if (k >= a.lo - 1e-9 && k <= a.hi + 1e-9)
      t.push_back({d, k % every == 0 ? decade_label(k) : "", true});
    for (int m = 2; m <= 9; ++m) {
      const double v = m * d, u = std::log10(v);
      if (u < a.lo || u > a.hi) continue;
      // With about two decades or less on show, 2 and 5 are labelled
      // too, so that the axis always carries a few numbers.
      const bool label = a.hi - a.lo < 2.2 && (m == 2 || m == 5);
      t.push_back({v, label ? plain_label(v) : "", false});
    }
  }
  return t;
}

// A point symbol of the given shape centred at (x, y).
std::string shape(int s, double x, double y, const std::string& colour) {
  const double r = 4.5;
  std::ostringstream o;
  const std::string fill = "fill=\"" + colour + "\" stroke=\"" + colour + "\"";
  switch (s % kShapes) {
    case 0:
      o << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << r << "\" " << fill
        << "/>";
      break;
    case 1:
      o << "<rect x=\"" << num(x - r * 0.85) << "\" y=\"" << num(y - r * 0.85) << "\" width=\""
        << num(2 * r * 0.85) << "\" height=\"" << num(2 * r * 0.85) << "\" " << fill << "/>";
      break;
    case 2:
      o << "<path d=\"M" << num(x) << "," << num(y - r * 1.15) << " L" << num(x + r) << ","
        << num(y + r * 0.75) << " L" << num(x - r) << "," << num(y + r * 0.75) << " Z\" " << fill
        << "/>";
      break;
    case 3:
      o << "<path d=\"M" << num(x) << "," << num(y - r * 1.2) << " L" << num(x + r) << "," << num(y)
        << " L" << num(x) << "," << num(y + r * 1.2) << " L" << num(x - r) << "," << num(y)
        << " Z\" " << fill << "/>";
      break;
    case 4:
      o << "<path d=\"M" << num(x) << "," << num(y + r * 1.15) << " L" << num(x + r) << ","
        << num(y - r * 0.75) << " L" << num(x - r) << "," << num(y - r * 0.75) << " Z\" " << fill
        << "/>";
      break;
    case 5:  // open circle
      o << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << r
        << "\" fill=\"white\" stroke=\"" << colour << "\" stroke-width=\"2\"/>";
      break;
    case 6:  // x cross
      o << "<path d=\"M" << num(x - r) << "," << num(y - r) << " L" << num(x + r) << ","
        << num(y + r) << " M" << num(x - r) << "," << num(y + r) << " L" << num(x + r) << ","
        << num(y - r) << "\" stroke=\"" << colour << "\" stroke-width=\"2.2\" fill=\"none\"/>";
      break;
    default:  // open square
      o << "<rect x=\"" << num(x - r * 0.85) << "\" y=\"" << num(y - r * 0.85) << "\" width=\""
        << num(2 * r * 0.85) << "\" height=\"" << num(2 * r * 0.85) << "\" fill=\"white\" stroke=\""
        << colour << "\" stroke-width=\"2\"/>";
  }
  return o.str();
}

}  // namespace

void write_svg(const Plot& plot, const fs::path& path) {
  Axis ax, ay;
  ax.log = plot.log_x;
  ay.log = plot.log_y;
  std::vector<double> xs, ys;
  for (const auto& s : plot.series)
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (ax.usable(s.x[i]) && ay.usable(s.y[i])) xs.push_back(s.x[i]), ys.push_back(s.y[i]);
  for (const auto& m : plot.markers)
    if (ax.usable(m.x) && ay.usable(m.y)) xs.push_back(m.x), ys.push_back(m.y);
  fit_axis(ax, xs);
  fit_axis(ay, ys);
  ax.p0 = kLeft, ax.p1 = kW - kRight;
  ay.p0 = kH - kBottom, ay.p1 = kTop;

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
    << "\" viewBox=\"0 0 " << kW << " " << kH
    << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\" font-size=\"13\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<defs><clipPath id=\"plotarea\"><rect x=\"" << kLeft << "\" y=\"" << kTop << "\" width=\""
    << kW - kLeft - kRight << "\" height=\"" << kH - kTop - kBottom << "\"/></clipPath></defs>\n";

  // Grid and ticks.
  const double x0 = kLeft, x1 = kW - kRight, y0 = kH - kBottom, y1 = kTop;
  for (const auto& t : ticks(ax)) {
    const double x = ax.px(t.value);
    o << "<line x1=\"" << num(x) << "\" y1=\"" << y1 << "\" x2=\"" << num(x) << "\" y2=\"" << y0
      << "\" stroke=\"" << (t.major ? "#d0d0d0" : "#eeeeee") << "\" stroke-width=\"1\"/>\n";
    o << "<line x1=\"" << num(x) << "\" y1=\"" << y0 << "\" x2=\"" << num(x) << "\" y2=\""
      << y0 + (t.major ? 7 : 4) << "\" stroke=\"black\"/>\n";
    if (!t.label.empty())
      o << "<text x=\"" << num(x) << "\" y=\"" << y0 + 24 << "\" text-anchor=\"middle\">" << t.label
        << "</text>\n";
  }
  for (const auto& t : ticks(ay)) {
    const double y = ay.px(t.value);
    o << "<line x1=\"" << x0 << "\" y1=\"" << num(y) << "\" x2=\"" << x1 << "\" y2=\"" << num(y)
      << "\" stroke=\"" << (t.major ? "#d0d0d0" : "#eeeeee") << "\" stroke-width=\"1\"/>\n";
    o << "<line x1=\"" << x0 - (t.major ? 7 : 4) << "\" y1=\"" << num(y) << "\" x2=\"" << x0
      << "\" y2=\"" << num(y) << "\" stroke=\"black\"/>\n";
    if (!t.label.empty())
      o << "<text x=\"" << x0 - 10 << "\" y=\"" << num(y + 5) << "\" text-anchor=\"end\">"
        << t.label << "</text>\n";
  }
  o << "<rect x=\"" << x0 << "\" y=\"" << y1 << "\" width=\"" << x1 - x0 << "\" height=\""
    << y0 - y1 << "\" fill=\"none\" stroke=\"black\"/>\n";

  // Title and axis labels.
  o << "<text x=\"" << kW / 2
    << "\" y=\"28\" text-anchor=\"middle\" font-size=\"16\" "
       "font-weight=\"bold\">"
    << esc(plot.title) << "</text>\n";
  o << "<text x=\"" << (x0 + x1) / 2 << "\" y=\"" << kH - 16 << "\" text-anchor=\"middle\">"
    << esc(plot.x_label) << "</text>\n";
  o << "<text transform=\"translate(22," << (y0 + y1) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">" << esc(plot.y_label) << "</text>\n";

  // Series: lines under points.
  o << "<g clip-path=\"url(#plotarea)\">\n";
  for (std::size_t k = 0; k < plot.series.size(); ++k) {
    const auto& s = plot.series[k];
    const std::string colour = kColours[k % std::size(kColours)];
    std::vector<std::pair<double, double>> pts;
    for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
      if (ax.usable(s.x[i]) && ay.usable(s.y[i])) pts.emplace_back(ax.px(s.x[i]), ay.px(s.y[i]));
    if (s.line && pts.size() > 1) {
      o << "<polyline fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.8\""
        << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << " points=\"";
      for (const auto& [x, y] : pts) o << num(x) << "," << num(y) << " ";
      o << "\"/>\n";
    }
    for (const auto& [x, y] : pts) o << shape(int(k), x, y, colour) << "\n";
  }
  o << "</g>\n";

  double leg_x = 0, leg_y = 0, leg_w = 0, leg_h = 0;  // the legend's box, if any
  // Legend in the corner of the plot with the fewest points under it.
  if (!plot.series.empty()) {
    std::size_t longest = 0;
    for (const auto& s : plot.series) longest = std::max(longest, s.name.size());
    const double lw = 44 + 7.2 * double(longest), lh = 10 + 19 * double(plot.series.size());
    struct Corner {
      double x, y;
    };
    const Corner corners[] = {
        {x1 - lw - 8, y1 + 8}, {x0 + 8, y1 + 8}, {x1 - lw - 8, y0 - lh - 8}, {x0 + 8, y0 - lh - 8}};
    std::size_t best = 0, best_count = std::numeric_limits<std::size_t>::max();
    for (std::size_t c = 0; c < 4; ++c) {
      std::size_t count = 0;
      for (std::size_t i = 0; i < xs.size(); ++i) {
        const double px = ax.px(xs[i]), py = ay.px(ys[i]);
        if (px >= corners[c].x - 6 && px <= corners[c].x + lw + 6 && py >= corners[c].y - 6 &&
            py <= corners[c].y + lh + 6)
          ++count;
      }
      if (count < best_count) best = c, best_count = count;
    }
    const auto [lx, ly] = corners[best];
    leg_x = lx, leg_y = ly, leg_w = lw, leg_h = lh;
    o << "<rect x=\"" << num(lx) << "\" y=\"" << num(ly) << "\" width=\"" << num(lw)
      << "\" height=\"" << num(lh)
      << "\" fill=\"white\" fill-opacity=\"0.88\" stroke=\"#888888\"/>\n";
    for (std::size_t k = 0; k < plot.series.size(); ++k) {
      const auto& s = plot.series[k];
      const std::string colour = kColours[k % std::size(kColours)];
      const double cy = ly + 14 + 19 * double(k);
      if (s.line)
        o << "<line x1=\"" << num(lx + 8) << "\" y1=\"" << num(cy) << "\" x2=\"" << num(lx + 32)
          << "\" y2=\"" << num(cy) << "\" stroke=\"" << colour << "\" stroke-width=\"1.8\""
          << (s.dashed ? " stroke-dasharray=\"6,4\"" : "") << "/>\n";
      o << shape(int(k), lx + 20, cy, colour) << "\n";
      o << "<text x=\"" << num(lx + 38) << "\" y=\"" << num(cy + 4.5) << "\">" << esc(s.name)
        << "</text>\n";
    }
  }
  // Markers: rings around the point, the label beside it, at the first of
  // four places that stays inside the plot and clear of the legend.
  for (const auto& m : plot.markers) {
    if (!ax.usable(m.x) || !ay.usable(m.y)) continue;
    const double x = ax.px(m.x), y = ay.px(m.y);
    o << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y)
      << "\" r=\"10\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/>\n";
    const double tw = 7.6 * double(m.label.size()), th = 14;
    struct Place {
      bool left;
      double baseline;
    };
    const Place places[] = {{false, y - 14}, {true, y - 14}, {false, y + 24}, {true, y + 24}};
    Place chosen = places[0];
    for (const Place& p : places) {
      const double bx = p.left ? x - 12 - tw : x + 12, by = p.baseline - th;
      const bool inside = bx >= x0 && bx + tw <= x1 && by >= y1 && p.baseline <= y0;
      const bool clear = leg_w == 0 || bx + tw < leg_x || bx > leg_x + leg_w ||
                         p.baseline < leg_y || by > leg_y + leg_h;
      if (inside && clear) {
        chosen = p;
        break;
      }
    }
    o << "<text x=\"" << num(chosen.left ? x - 12 : x + 12) << "\" y=\"" << num(chosen.baseline)
      << "\" text-anchor=\"" << (chosen.left ? "end" : "start")
      << "\" font-weight=\"bold\" stroke=\"white\" stroke-width=\"3\" "
      << "paint-order=\"stroke\">" << esc(m.label) << "</text>\n";
  }
  o << "</svg>\n";

  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path.string());
  f << o.str();
}

// ---------------------------------------------------------------------------
// Analysis

double loglog_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0) || !std::isfinite(x[i]) || !std::isfinite(y[i])) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
    ++n;
  }
  if (n < 2) return std::numeric_limits<double>::quiet_NaN();
  const double d = double(n) * sxx - sx * sx;
  if (std::abs(d) < 1e-300) return std::numeric_limits<double>::quiet_NaN();
  return (double(n) * sxy - sx * sy) / d;
}

std::vector<std::size_t> pareto_front(const std::vector<double>& cost,
                                      const std::vector<double>& error) {
  const std::size_t n = std::min(cost.size(), error.size());
  auto ok = [&](std::size_t i) { return std::isfinite(cost[i]) && std::isfinite(error[i]); };
  std::vector<std::size_t> front;
  // Quadratic, and plainly the definition: sweeps have at most a few
  // hundred points.
  for (std::size_t i = 0; i < n; ++i) {
    if (!ok(i)) continue;
    bool dominated = false;
    for (std::size_t j = 0; j < n && !dominated; ++j)
      dominated = j != i && ok(j) && cost[j] <= cost[i] && error[j] <= error[i] &&
                  (cost[j] < cost[i] || error[j] < error[i]);
    if (!dominated) front.push_back(i);
  }
  std::stable_sort(front.begin(), front.end(), [&](std::size_t a, std::size_t b) {
    return cost[a] < cost[b] || (cost[a] == cost[b] && error[a] < error[b]);
  });
  return front;
}

void splice(const fs::path& doc, std::string_view key, std::string_view content) {
  if (doc.empty()) return;
  std::string text;
  {
    std::ifstream in(doc, std::ios::binary);
    if (in) {
      std::ostringstream ss;
      ss << in.rdbuf();
      text = ss.str();
    }
  }
  const std::string begin = "<!-- bench:" + std::string(key) + " -->";
  const std::string end = "<!-- /bench:" + std::string(key) + " -->";
  std::string body(content);
  if (body.empty() || body.back() != '\n') body += '\n';

  const std::size_t b = text.find(begin);
  const std::size_t e = b == std::string::npos ? std::string::npos : text.find(end, b);
  if (b != std::string::npos && e != std::string::npos) {
    text.replace(b + begin.size(), e - (b + begin.size()), "\n" + body);
  } else {
    if (!text.empty() && text.back() != '\n') text += '\n';
    text += "\n" + begin + "\n" + body + end + "\n";
  }
  // Written beside and renamed, so a reader never sees half a page.
  const fs::path tmp = doc.string() + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
    out << text;
  }
  fs::rename(tmp, doc);
}

}  // namespace alloy::bench
