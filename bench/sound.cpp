// Sound, measured: how late a strike is heard, and how exact the synthesis is.
//
//   onset      a ball dropped on a pinned bell through the real chain (rigid
//              body -> collisions -> sound_from_collisions -> sound). The
//              analytic moment of impact is t* = sqrt(2 d / g); the error is
//              the time of the first non-zero sample minus t*, swept over the
//              world's step. It is a latency, not noise: the touch is found
//              at the end of a step, and the paper's one-step delay between
//              stages adds two more.
//   synthesis  one mode rendered by ModalSynth against the exact damped
//              sinusoid A e^{-a t} sin(2 pi f t) at every sample, swept over
//              the sample rate, with the cost per simulated second of 1 to 32
//              ringing voices.
//
// `alloy_bench_sound [--quick] [--out DIR] [--docs FILE]`; KEY "sound".
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "bench/common/bench_common.hpp"
#include "resolvers/plugins.hpp"
#include "resolvers/sound/modal_synth.hpp"
#include "resolvers/sound/sound_plugins.hpp"
#include "resolvers/sound/sound_resolver.hpp"
#include "tests/scenes/rigid_scenes.hpp"

namespace {

using namespace alloy;
using namespace alloy::bench;

constexpr double kG = 9.81;
constexpr double kDrop = 0.1;  // gap between ball and bell, m
constexpr double kBallRadius = 0.02, kBellTop = 0.025;

struct OnsetRun {
  double dt = 0;
  int substeps = 1;
  double onset_error = 0;  // s, first audible sample minus the analytic impact
  double cost = 0;         // CPU s per simulated s
};

OnsetRun onset(double dt, int substeps) {
  PluginRegistry registry;
  register_native_plugins(registry);
  sound::register_sound_plugins(registry);
  WorldDef def;
  def.dt = dt;
  def.settings["rigid_body"].set("substeps", std::int64_t(substeps));
  World w(registry, def);
  const ObjectId bell = scenes::add_box(w, {0, 0, 0}, {0.2, 0.05, 0.05}, 2.0, {}, "bell");
  w.set(bell, "pinned", true);
  w.set(bell, "acoustic", std::string("bell"));
  w.set(bell, "pitch", 1000.0);
  w.set(bell, "decay", 2.0);
  scenes::add_sphere(w, {0, kBellTop + kBallRadius + kDrop, 0}, kBallRadius, 0.1, "ball");
  const double seconds = 2.0;  // long enough for the cost to be above the timer's noise
  OnsetRun r{dt, substeps};
  r.cost = cpu_time([&] { w.run(std::uint64_t(std::llround(seconds / dt))); }) / seconds;
  const auto& s = dynamic_cast<sound::SoundResolver&>(*w.stage("sound"));
  const auto samples = s.samples();
  const auto first = std::find_if(samples.begin(), samples.end(), [](float x) { return x != 0; });
  const double heard = first == samples.end()
                           ? NAN
                           : s.start_time() + double(first - samples.begin()) / s.sample_rate();
  r.onset_error = heard - std::sqrt(2 * kDrop / kG);
  return r;
}

struct SynthRun {
  double rate = 0;
  double max_error = 0;  // relative to the amplitude, over the whole render
};

SynthRun synthesis(double rate, double seconds) {
  const double f = 4640, a = 0.5, t60 = 2.0;
  sound::ModalSynth synth({.sample_rate = rate, .max_voices = 1, .floor = 0});
  const sound::Mode m{.frequency = f, .amplitude = a, .t60 = t60};
  synth.strike({&m, 1});
  std::vector<float> out(std::size_t(std::llround(seconds * rate)), 0.0f);
  synth.render(out);
  const double decay = sound::kLn1000 / t60;
  double worst = 0;
  for (std::size_t k = 0; k < out.size(); ++k) {
    const double t = double(k + 1) / rate;  // the first sample is one sample after the strike
    const double exact = a * std::exp(-decay * t) * std::sin(2 * std::numbers::pi * f * t);
    worst = std::max(worst, std::abs(double(out[k]) - exact));
  }
  return {rate, worst / a};
}

/// CPU seconds per simulated second for `voices` voices of `modes` modes each.
double synth_cost(double rate, int voices, int modes, double seconds) {
  sound::ModalSynth synth({.sample_rate = rate, .max_voices = std::size_t(voices), .floor = 0});
  std::vector<sound::Mode> ms;
  for (int k = 0; k < modes; ++k)
    ms.push_back({.frequency = 300.0 * (k + 1), .amplitude = 0.01, .t60 = 60});
  for (int v = 0; v < voices; ++v) synth.strike(ms);
  const std::size_t block = std::size_t(rate / 240);  // one step's worth
  std::vector<float> out(block);
  const int blocks = int(seconds * 240);
  return cpu_time([&] {
           for (int b = 0; b < blocks; ++b) {
             std::fill(out.begin(), out.end(), 0.0f);
             synth.render(out);
           }
         }) /
         seconds;
}

}  // namespace

int main(int argc, char** argv) {
  const Options opt = Options::parse(argc, argv, "alloy_bench_sound");
  const std::vector<double> rates_hz =
      opt.quick ? std::vector<double>{60, 240} : std::vector<double>{60, 120, 240, 480, 960, 1920};
  const std::vector<int> substeps = opt.quick ? std::vector<int>{1} : std::vector<int>{1, 4};
  const std::vector<double> sample_rates =
      opt.quick ? std::vector<double>{48000} : std::vector<double>{22050, 44100, 48000, 96000};

  std::vector<OnsetRun> runs;
  {
    Progress bar("sound: strike onset", rates_hz.size() * substeps.size(), opt.progress);
    for (int n : substeps)
      for (double hz : rates_hz) {
        runs.push_back(onset(1.0 / hz, n));
        bar.tick();
      }
  }
  std::vector<SynthRun> synth;
  std::vector<std::array<double, 3>> costs;  // per sample rate: 1, 8, 32 voices
  {
    Progress bar("sound: synthesis", sample_rates.size(), opt.progress);
    for (double fs : sample_rates) {
      synth.push_back(synthesis(fs, opt.quick ? 0.2 : 2.0));
      const double t = opt.quick ? 0.2 : 2.0;
      costs.push_back({synth_cost(fs, 1, 8, t), synth_cost(fs, 8, 8, t), synth_cost(fs, 32, 8, t)});
      bar.tick();
    }
  }

  // --- outputs ---------------------------------------------------------------------
  Csv csv(opt.file("sound.csv"),
          {"part", "dt_s", "substeps", "sample_rate_hz", "error", "cost_s_per_s"});
  for (const auto& r : runs)
    csv.row({"onset", Csv::cell(r.dt), Csv::cell(r.substeps), "48000", Csv::cell(r.onset_error),
             Csv::cell(r.cost)});
  for (std::size_t i = 0; i < synth.size(); ++i)
    csv.row({"synthesis", "", "", Csv::cell(synth[i].rate), Csv::cell(synth[i].max_error),
             Csv::cell(costs[i][0])});

  Plot plot;
  plot.title = "Sound: strike onset error (ball dropped 0.1 m on a bell)";
  plot.x_label = "run time per simulated second (s)";
  plot.y_label = "onset after the analytic impact (s)";
  for (int n : substeps) {
    Series s;
    s.name = n == 1 ? "rigid_body substeps 1" : "rigid_body substeps " + std::to_string(n);
    for (const auto& r : runs)
      if (r.substeps == n) s.x.push_back(r.cost), s.y.push_back(r.onset_error);
    plot.series.push_back(s);
  }
  for (const auto& r : runs)
    if (r.substeps == 1 && std::abs(r.dt - 1.0 / 240) < 1e-12)
      plot.markers.push_back({r.cost, r.onset_error, "default dt 1/240 s"});
  write_svg(plot, opt.file("sound_onset.svg"));

  Table onset_table({"dt", "substeps", "onset error (ms)", "in steps", "CPU s per simulated s"});
  std::vector<double> dts, errs;
  for (const auto& r : runs) {
    onset_table.row({"1/" + std::to_string(std::lround(1 / r.dt)), std::to_string(r.substeps),
                     fmt(r.onset_error * 1e3), fmt(r.onset_error / r.dt), fmt(r.cost)});
    if (r.substeps == 1) dts.push_back(r.dt), errs.push_back(r.onset_error);
  }
  const double order = loglog_slope(dts, errs);
  Table synth_table({"sample rate (Hz)", "max |error| / amplitude over the render",
                     "CPU s per simulated s: 1 voice", "8 voices", "32 voices"});
  for (std::size_t i = 0; i < synth.size(); ++i)
    synth_table.row({fmt(synth[i].rate, 5), fmt(synth[i].max_error), fmt(costs[i][0]),
                     fmt(costs[i][1]), fmt(costs[i][2])});

  std::string md =
      "Strike onset (plot: [sound_onset.svg](bench/sound_onset.svg)); observed order of the "
      "onset error in dt: " +
      fmt(order) + ".\n\n" + onset_table.str() +
      "\nSynthesis of one 4640 Hz mode (T60 2 s, amplitude 0.5) against the exact damped "
      "sinusoid; cost of voices of 8 modes each:\n\n" +
      synth_table.str();
  std::printf("%s\n", md.c_str());
  if (!opt.quick) splice(opt.docs, "sound", md);

  // The claims this bench stands on: a strike is heard within three steps of
  // the touch, and the synthesis is exact to float resolution.
  bool ok = true;
  for (const auto& r : runs)
    if (!(r.onset_error > 0 && r.onset_error < 3.5 * r.dt + 1e-9)) ok = false;
  for (const auto& s : synth)
    if (!(s.max_error < 1e-5)) ok = false;
  return ok ? 0 : 1;
}
