#include "apps/alloy/event_log.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

namespace alloy::app {

EventLog::EventLog(const std::string& path, std::uint64_t bytes_per_mod)
    : path_(path), temp_(path + ".tmp"), bytes_per_mod_(bytes_per_mod) {
  out_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError("cannot write events file '" + path + "'");
}

EventLog::~EventLog() {
  if (!closed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void EventLog::write(const World& world, const Event& e, const std::string& mod) {
  Written* w = mod.empty() ? nullptr : &by_mod_[mod];
  if (w && w->bytes >= bytes_per_mod_) {  // counted, not formatted: a flood costs little
    ++w->dropped_events;
    w->dropped_bytes += e.type.size() + e.text.size();
    return;
  }
  nlohmann::ordered_json j;
  j["step"] = e.step;
  j["time"] = e.time;
  j["type"] = e.type;
  if (!e.source.empty()) j["source"] = e.source;
  if (!e.a.is_null()) j["a"] = world.describe(e.a);
  if (!e.b.is_null()) j["b"] = world.describe(e.b);
  for (const auto& [k, v] : e.values) j[k] = std::isfinite(v) ? nlohmann::ordered_json(v) : nullptr;
  if (!e.text.empty()) j["text"] = e.text;
  const std::string line = j.dump();
  if (w) w->bytes += line.size() + 1;
  out_ << line << '\n';
}

void EventLog::close(const World& world) {
  for (const auto& [mod, w] : by_mod_)
    if (w.dropped_events > 0) {
      nlohmann::ordered_json j;
      j["step"] = world.step_count();
      j["time"] = world.time();
      j["type"] = "events_dropped";
      j["source"] = mod;
      j["events"] = w.dropped_events;
      j["text"] = "mod '" + mod + "' emitted more than " + std::to_string(bytes_per_mod_ >> 20) +
                  " MiB of events in this run; the rest were not written";
      out_ << j.dump() << '\n';
    }
  out_.flush();
  if (!out_) throw std::runtime_error("writing events file '" + path_ + "' failed");
  out_.close();
  std::filesystem::rename(temp_, path_);
  closed_ = true;
}

void Narrator::line(const std::string& text) {
  flush();
  out_ << text << '\n';
}

void Narrator::narrate(const World& world, const Event& e, const std::string& mod) {
  ++counts_[e.type];
  if (!mod.empty() && narrated_[mod] >= bytes_per_mod_) {
    dropped_[mod] += e.type.size() + e.text.size();
    return;
  }
  // Rare and serious: always told, on its own line.
  if (e.type == "non_finite" || e.type == "out_of_bounds") {
    flush();
    char head[64];
    std::snprintf(head, sizeof head, "step %6llu  t=%7.3f s  ", (unsigned long long)e.step, e.time);
    out_ << head << frozen_message(world, e) << '\n';
    return;
  }
  const auto key = std::make_tuple(e.type, e.a, e.b);
  auto it = last_seen_.find(key);
  const bool novel = it == last_seen_.end() || e.time - it->second >= 1.0;
  last_seen_[key] = e.time;
  const bool in_window = std::fmod(e.time, 1.0) < window_;
  if (!novel && !in_window) {
    ++folded_;
    return;
  }

  std::string who;
  if (!e.a.is_null()) who = world.describe(e.a);
  if (!e.b.is_null()) who += " - " + world.describe(e.b);
  if (e.step == line_step_ && e.type == line_type_ && line_mod_ == mod && e.values.empty() &&
      e.text.empty() && !who.empty()) {
    line_ += ", " + who;  // another element of the same change in the same step
    return;
  }
  flush();
  line_mod_ = mod;
  std::string what = e.type;
  for (char& c : what)
    if (c == '_') c = ' ';
  char head[64];
  std::snprintf(head, sizeof head, "step %6llu  t=%7.3f s  ", (unsigned long long)e.step, e.time);
  line_ = head + what;
  if (!who.empty()) line_ += ": " + who;
  for (const auto& [k, v] : e.values) {
    char num[48];
    std::snprintf(num, sizeof num, "%.4g", v);
    line_ += "  " + k + "=" + num;
  }
  if (!e.text.empty()) line_ += "  (" + e.text + ")";
  line_step_ = e.values.empty() && e.text.empty() ? e.step : ~0ull;
  line_type_ = e.type;
}

void Narrator::flush() {
  if (!line_.empty()) {
    if (!line_mod_.empty()) {
      // Past the mod's share the line is cut, once; later ones are dropped (narrate).
      std::uint64_t& used = narrated_[line_mod_];
      const std::uint64_t room = bytes_per_mod_ > used ? bytes_per_mod_ - used : 0;
      if (line_.size() + 1 > room) {
        dropped_[line_mod_] += line_.size() + 1 - room;
        line_.resize(room > 0 ? room - 1 : 0);
      }
      used += line_.size() + 1;
    }
    out_ << line_ << '\n';
  }
  line_.clear();
  line_mod_.clear();
  line_step_ = ~0ull;
}

void Narrator::summary(const World& world, double wall_seconds) {
  flush();
  char line[160];
  std::snprintf(line, sizeof line,
                "ran %llu steps of %.6g s: %.3f s simulated in %.3f s wall (%.1fx real time)\n",
                (unsigned long long)world.step_count(), world.dt(), world.time(), wall_seconds,
                wall_seconds > 0 ? world.time() / wall_seconds : 0.0);
  out_ << line;
  if (!counts_.empty()) {
    out_ << "events:";
    for (const auto& [type, n] : counts_) out_ << " " << type << "=" << n;
    if (folded_) out_ << " (" << folded_ << " repeats not narrated)";
    out_ << '\n';
  }
  for (const auto& [mod, bytes] : dropped_)
    out_ << "narration of mod '" << mod << "' cut at " << (bytes_per_mod_ >> 10)
         << " KiB: " << bytes << " more bytes dropped\n";
}

}  // namespace alloy::app
