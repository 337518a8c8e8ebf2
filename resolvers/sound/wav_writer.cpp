#include "resolvers/sound/wav_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace alloy::sound {

namespace {

// Byte by byte, so the file is little-endian whatever the host is.
void put16(std::vector<char>& out, std::uint16_t v) {
  out.push_back(char(v & 0xff));
  out.push_back(char(v >> 8));
}
void put32(std::vector<char>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(char((v >> (8 * i)) & 0xff));
}
void put_tag(std::vector<char>& out, const char (&tag)[5]) {
  out.insert(out.end(), tag, tag + 4);
}

}  // namespace

WavInfo write_wav(const std::string& path, std::span<const float> samples, int sample_rate,
                  WavLevel level) {
  constexpr std::uint16_t kChannels = 1, kBits = 16, kBlockAlign = kChannels * kBits / 8;
  if (sample_rate <= 0) throw std::runtime_error(path + ": sample rate must be positive");
  // RIFF sizes are 32-bit: the data chunk may hold at most 4 GiB - 36 bytes.
  if (samples.size() > (0xffffffffull - 36) / kBlockAlign)
    throw std::runtime_error(path + ": too many samples for a WAV file");

  WavInfo info;
  info.frames = samples.size();
  for (float s : samples) info.peak = std::max(info.peak, double(std::abs(s)));
  if (level == WavLevel::fit && info.peak > 1) info.scale = 1 / info.peak;

  const auto data_bytes = std::uint32_t(samples.size() * kBlockAlign);
  std::vector<char> bytes;
  bytes.reserve(44 + data_bytes);
  put_tag(bytes, "RIFF");
  put32(bytes, 36 + data_bytes);  // everything after this field
  put_tag(bytes, "WAVE");
  put_tag(bytes, "fmt ");
  put32(bytes, 16);  // PCM fmt chunk size
  put16(bytes, 1);   // format: PCM
  put16(bytes, kChannels);
  put32(bytes, std::uint32_t(sample_rate));
  put32(bytes, std::uint32_t(sample_rate) * kBlockAlign);  // byte rate
  put16(bytes, kBlockAlign);
  put16(bytes, kBits);
  put_tag(bytes, "data");
  put32(bytes, data_bytes);
  for (float s : samples) {
    double x = double(s) * info.scale;
    if (!std::isfinite(x)) x = 0;  // a NaN must not become a full-scale click
    if (x > 1 || x < -1) {
      ++info.clipped;
      x = std::clamp(x, -1.0, 1.0);
    }
    // Symmetric scaling by 32767 keeps 0 at 0 and +-1 at +-32767.
    put16(bytes, std::uint16_t(std::int16_t(std::lround(x * 32767))));
  }

  // Temp file in the same directory, so the rename is atomic (same file system).
  const std::filesystem::path target(path);
  std::filesystem::path temp = target;
  temp += ".tmp";
  {
    std::ofstream f(temp, std::ios::binary | std::ios::trunc);
    if (!f) throw std::runtime_error(path + ": cannot write (" + std::strerror(errno) + ")");
    f.write(bytes.data(), std::streamsize(bytes.size()));
    f.flush();
    if (!f) {
      f.close();
      std::error_code ignored;
      std::filesystem::remove(temp, ignored);
      throw std::runtime_error(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw std::runtime_error(path + ": cannot replace the file (" + ec.message() + ")");
  }
  return info;
}

}  // namespace alloy::sound
