// The doorbell (mods/doorbell, docs/doorbell.md): built from kit parts only,
// rung by nothing but the physics. These tests run its scenes headless and
// check what the paper (4.1) says a doorbell does, then check it again with
// the step halved and the battery 10 % weaker and stronger.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/alloy/commands.hpp"
#include "tests/doorbell/doorbell_support.hpp"
#include "tests/resolvers/sound/goertzel.hpp"

namespace alloy::doorbell::test {
namespace {

constexpr const char* kScene = "mods/doorbell";
constexpr const char* kOpen = "mods/doorbell/switch_open.lua";
constexpr const char* kLifted = "mods/doorbell/switch_lifted.lua";
constexpr double kSwitchDropped =
    0.5;  // the scenes' timeline: at(0.5, "switch_bar", { pinned = false })
constexpr double kSwitchLifted =
    3.0;  // switch_lifted.lua: at(3.0, "switch_bar", { pinned = true, ... })

std::string describe(const Cycle& c) {
  std::ostringstream s;
  s << "closed " << c.closed << ", magnet on " << c.on << ", striker left " << c.left << ", broken "
    << c.broken << ", struck " << c.struck << " (" << c.closures << " closures)";
  return s.str();
}

/// What every ringing run must show: at least `min_strikes`, a steady period
/// (max - min of the intervals under `max_spread` of their mean), and the
/// paper's chain before every strike, each cycle clean (one closure) after
/// the first.
void expect_rings_steadily(const RunResult& r, std::size_t min_strikes, double max_spread) {
  const auto t = r.strikes();
  ASSERT_GE(t.size(), min_strikes);
  // The period from the second strike on: the first interval starts from the
  // striker at rest, a start-up transient (as the first cycle's closures are
  // below). With 10 % more emf it is 18 steps, then 16 steps every time.
  const Intervals iv = intervals(std::vector<double>(t.begin() + 1, t.end()));
  EXPECT_LT(iv.spread(), max_spread)
      << "intervals from " << iv.min << " to " << iv.max << " s, mean " << iv.mean;
  const auto cs = cycles(r);
  ASSERT_EQ(cs.size(), t.size());
  for (std::size_t i = 0; i < cs.size(); ++i) {
    EXPECT_TRUE(cs[i].in_order) << "strike " << i << ": " << describe(cs[i]);
    if (i > 0) {
      EXPECT_EQ(cs[i].closures, 1) << "strike " << i << ": " << describe(cs[i]);
    }
  }
}

TEST(Doorbell, WithTheSwitchClosedTheBellRingsAtASteadyPeriod) {
  const RunResult r = run_scene(kScene);
  EXPECT_DOUBLE_EQ(r.dt, 1.0 / 240);
  ASSERT_EQ(r.steps, 2400u);
  const auto t = r.strikes();
  ASSERT_FALSE(t.empty());
  EXPECT_GT(t.front(), kSwitchDropped) << "nothing rings before the switch bar is let go";
  EXPECT_LT(t.front(), kSwitchDropped + 0.25) << "it rings at once";
  expect_rings_steadily(r, 100, 0.10);
  // Measured (docs/doorbell.md): 133 strikes, every 17 steps (0.0708 s),
  // since session 20's coupling (the coil pulls with the circuit's current of
  // the step, not the one predicted a step on; before it, 142 strikes every
  // 16 steps). The converged period, from the second strike, is 0.0694 s at
  // 1/1920 s (0.0688 and 0.0678 s at 1/480 and 1/960 s: the bell locks to
  // whole steps), so 17 steps is within 2.1 % of it (16 was 3.9 % short).
  const Intervals iv = intervals(t);
  EXPECT_NEAR(iv.mean, 17.0 / 240, 0.5 / 240);
  EXPECT_GE(t.size(), 130u);
}

TEST(Doorbell, EachCycleFollowsThePapersChainStepByStep) {
  const RunResult r = run_scene(kScene, {.seconds = 2});
  const auto cs = cycles(r);
  ASSERT_GE(cs.size(), 10u);
  for (std::size_t i = 1; i < cs.size(); ++i) {
    const Cycle& c = cs[i];
    ASSERT_TRUE(c.in_order) << describe(c);
    // The one-step delays of the method (paper 3.2, 4.1.2-4.1.5): a circuit
    // closed in step n makes a magnet in step n + 1; a contact ended in step
    // n breaks the circuit in step n + 1.
    EXPECT_EQ(c.on, c.closed + 1) << describe(c);
    EXPECT_EQ(c.broken, c.left + 1) << describe(c);
    // The bell is struck after the circuit broke: the striker flies the last
    // millimetres with the magnet off.
    EXPECT_GT(c.struck, c.broken) << describe(c);
  }
  // Every strike rings the bell at its pitch, through the striker's hammer.
  for (const Record* s : r.of("sound", "bell")) {
    EXPECT_EQ(s->b, "hammer");
    EXPECT_NEAR(s->value("pitch"), 4640, 1);
    EXPECT_GT(s->value("amplitude"), 0.02);
  }
}

TEST(Doorbell, WithTheSwitchLeftOpenItNeverRings) {
  const RunResult r = run_scene(kOpen);
  EXPECT_EQ(r.steps, 2400u);
  EXPECT_TRUE(r.of("sound").empty());
  EXPECT_TRUE(r.of("circuit_closed", "coil").empty());
  EXPECT_TRUE(r.of("electromagnet_on").empty());
  EXPECT_EQ(r.final_coil_current, 0.0);
  // The striker rests: its contact finger touched the interrupter once, at
  // the start, and never left it.
  EXPECT_TRUE(r.of("contact_ended", "finger").empty());
}

TEST(Doorbell, LiftingTheSwitchBarAwayStopsIt) {
  const RunResult r = run_scene(kLifted);
  const auto t = r.strikes();
  ASSERT_GE(t.size(), 20u) << "it rang while the switch was closed";
  EXPECT_LT(t.back(), kSwitchLifted + 0.1) << "at most the blow already on its way";
  const auto opened = r.of("circuit_opened", "coil");
  ASSERT_FALSE(opened.empty());
  EXPECT_LT(opened.back()->time, kSwitchLifted + 0.1);
  for (const Record* e : r.of("circuit_closed", "coil")) EXPECT_LT(e->time, kSwitchLifted + 0.01);
  EXPECT_EQ(r.final_coil_current, 0.0);
}

// --- the same with small changes: robust, not at a knife edge ----------------------

TEST(DoorbellRobustness, StillRingsSteadilyWithHalfTheStep) {
  const RunResult r = run_scene(kScene, {.dt = 1.0 / 480});
  expect_rings_steadily(r, 100, 0.10);
}

TEST(DoorbellRobustness, StillRingsSteadilyWithTenPercentLessEmf) {
  const RunResult r = run_scene(kScene, {.emf_scale = 0.9});
  expect_rings_steadily(r, 80, 0.10);
}

TEST(DoorbellRobustness, StillRingsSteadilyWithTenPercentMoreEmf) {
  const RunResult r = run_scene(kScene, {.emf_scale = 1.1});
  expect_rings_steadily(r, 100, 0.10);
}

TEST(DoorbellRobustness, StillRingsSteadilyWithHalfTheStepAndTenPercentLessEmf) {
  const RunResult r = run_scene(kScene, {.dt = 1.0 / 480, .emf_scale = 0.9});
  expect_rings_steadily(r, 80, 0.10);
}

// --- what it sounds like: the WAV of `alloy run mods/doorbell --audio` --------------

struct Wav {
  double rate = 0;
  std::vector<float> samples;
};

std::uint32_t u32(const std::string& s, std::size_t at) {
  return std::uint32_t(std::uint8_t(s[at])) | std::uint32_t(std::uint8_t(s[at + 1])) << 8 |
         std::uint32_t(std::uint8_t(s[at + 2])) << 16 |
         std::uint32_t(std::uint8_t(s[at + 3])) << 24;
}
std::uint16_t u16(const std::string& s, std::size_t at) {
  return std::uint16_t(std::uint8_t(s[at]) | std::uint8_t(s[at + 1]) << 8);
}

Wav read_wav(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string s{std::istreambuf_iterator<char>(in), {}};
  Wav w;
  if (s.size() < 44 || s.compare(0, 4, "RIFF") != 0 || s.compare(8, 4, "WAVE") != 0) return w;
  std::size_t at = 12;
  std::uint16_t bits = 0, channels = 0;
  while (at + 8 <= s.size()) {
    const std::string id = s.substr(at, 4);
    const std::uint32_t size = u32(s, at + 4);
    if (id == "fmt ") {
      channels = u16(s, at + 10);
      w.rate = u32(s, at + 12);
      bits = u16(s, at + 22);
    } else if (id == "data" && bits == 16 && channels == 1) {
      for (std::size_t i = 0; i + 1 < size && at + 8 + i + 1 < s.size(); i += 2)
        w.samples.push_back(float(std::int16_t(u16(s, at + 8 + i))) / 32768.0f);
    }
    at += 8 + size + (size & 1);
  }
  return w;
}

TEST(DoorbellSound, TheWavHasTheBellsPitchAfterEachStrikeAndSilenceBefore) {
  namespace fs = std::filesystem;
  const fs::path dir =
      fs::temp_directory_path() / ("alloy_doorbell_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string wav = (dir / "bell.wav").string(), events = (dir / "bell.jsonl").string();
  const std::string scene = source(kScene).string();
  const char* argv[] = {"alloy",   "run",     scene.c_str(), "--seconds", "3",
                        "--quiet", "--audio", wav.c_str(),   "--events",  events.c_str()};
  std::ostringstream out, err;
  ASSERT_EQ(app::run_cli(int(std::size(argv)), argv, out, err), app::kExitOk) << err.str();

  const Wav w = read_wav(wav);
  ASSERT_EQ(w.rate, 48000);
  ASSERT_NEAR(double(w.samples.size()), 3 * 48000, 1);
  std::vector<double> strikes;
  double pitch = 0;
  std::ifstream in(events);
  for (std::string line; std::getline(in, line);) {
    const auto j = nlohmann::json::parse(line);
    if (j["type"] == "sound" && j["a"] == "bell") {
      strikes.push_back(j["time"].get<double>());
      pitch = j["pitch"].get<double>();
    }
  }
  ASSERT_GE(strikes.size(), 20u);
  ASSERT_GT(pitch, 1000);

  // Before the switch closes: silence (not a sample off zero).
  const auto before = sound::test::window(w.samples, w.rate, 0, kSwitchDropped);
  EXPECT_LT(sound::test::rms(before), 1e-6);

  // After each strike, until the next: the bell's pitch dominates its
  // neighbourhood (10 % either side, between the bell's own partials).
  const double end = double(w.samples.size()) / w.rate;
  for (std::size_t i = 0; i < strikes.size(); ++i) {
    const double t0 = strikes[i],
                 t1 = std::min({i + 1 < strikes.size() ? strikes[i + 1] : end, t0 + 0.05, end});
    if (t1 - t0 < 0.02) continue;  // the run ends right after it
    const auto x = sound::test::window(w.samples, w.rate, t0, t1);
    const double at = sound::test::goertzel(x, pitch, w.rate);
    const double low = sound::test::goertzel(x, 0.9 * pitch, w.rate);
    const double high = sound::test::goertzel(x, 1.1 * pitch, w.rate);
    EXPECT_GT(at, 0.005) << "strike " << i << " at " << t0 << " s";
    EXPECT_GT(at, 30 * std::max(low, high))
        << "strike " << i << " at " << t0 << " s: " << at << " at the pitch, " << low << " and "
        << high << " beside it";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace alloy::doorbell::test
