// Tests for resolvers/sound/wav_writer.hpp: the file a player opens. The
// header is parsed here byte by byte (not by our own reader) so that a wrong
// field cannot pass by being wrong the same way twice.
#include "resolvers/sound/wav_writer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

namespace alloy::sound {
namespace {

namespace fs = std::filesystem;

std::vector<unsigned char> read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
std::uint32_t u32(const std::vector<unsigned char>& b, std::size_t at) {
  return b[at] | (b[at + 1] << 8) | (b[at + 2] << 16) | (std::uint32_t(b[at + 3]) << 24);
}
std::uint16_t u16(const std::vector<unsigned char>& b, std::size_t at) {
  return std::uint16_t(b[at] | (b[at + 1] << 8));
}
std::int16_t sample(const std::vector<unsigned char>& b, std::size_t i) {
  return std::int16_t(u16(b, 44 + 2 * i));
}
std::string tag(const std::vector<unsigned char>& b, std::size_t at) {
  return std::string(b.begin() + std::ptrdiff_t(at), b.begin() + std::ptrdiff_t(at + 4));
}

class WavWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("alloy_wav_test_" +
           std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir);
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

TEST_F(WavWriterTest, HeaderAndSamplesRoundTrip) {
  const int rate = 44100;
  const double seconds = 0.75;
  std::vector<float> x(std::size_t(seconds * rate));
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = float(0.8 * std::sin(2 * M_PI * 440 * double(i) / rate));
  const fs::path path = dir / "tone.wav";
  const WavInfo info = write_wav(path.string(), x, rate);
  EXPECT_EQ(info.frames, x.size());
  EXPECT_EQ(info.clipped, 0u);

  const auto b = read_bytes(path);
  ASSERT_EQ(b.size(), 44 + 2 * x.size());
  EXPECT_EQ(tag(b, 0), "RIFF");
  EXPECT_EQ(u32(b, 4), b.size() - 8);
  EXPECT_EQ(tag(b, 8), "WAVE");
  EXPECT_EQ(tag(b, 12), "fmt ");
  EXPECT_EQ(u32(b, 16), 16u);         // PCM fmt chunk
  EXPECT_EQ(u16(b, 20), 1u);          // PCM
  EXPECT_EQ(u16(b, 22), 1u);          // mono
  EXPECT_EQ(u32(b, 24), 44100u);      // sample rate
  EXPECT_EQ(u32(b, 28), 44100u * 2);  // byte rate
  EXPECT_EQ(u16(b, 32), 2u);          // block align
  EXPECT_EQ(u16(b, 34), 16u);         // bits per sample
  EXPECT_EQ(tag(b, 36), "data");
  const std::uint32_t frames = u32(b, 40) / 2;
  EXPECT_EQ(frames, std::uint32_t(std::llround(seconds * rate)));  // duration * rate
  for (std::size_t i = 0; i < x.size(); i += 97)
    EXPECT_NEAR(sample(b, i) / 32767.0, x[i], 0.5 / 32767 + 1e-7) << i;
  EXPECT_FALSE(fs::exists(dir / "tone.wav.tmp"));
}

TEST_F(WavWriterTest, LoudSamplesAreClippedOrFitted) {
  const std::vector<float> x = {0.5f, 2.0f, -4.0f, 0.0f};
  const fs::path clip = dir / "clip.wav", fit = dir / "fit.wav";
  const WavInfo c = write_wav(clip.string(), x, 48000, WavLevel::clip);
  EXPECT_EQ(c.clipped, 2u);
  EXPECT_DOUBLE_EQ(c.peak, 4.0);
  const auto bc = read_bytes(clip);
  EXPECT_EQ(sample(bc, 1), 32767);
  EXPECT_EQ(sample(bc, 2), -32767);
  const WavInfo f = write_wav(fit.string(), x, 48000, WavLevel::fit);
  EXPECT_DOUBLE_EQ(f.scale, 0.25);
  EXPECT_EQ(f.clipped, 0u);
  const auto bf = read_bytes(fit);
  EXPECT_EQ(sample(bf, 0), std::int16_t(std::lround(0.125 * 32767)));
  EXPECT_EQ(sample(bf, 2), -32767);
}

TEST_F(WavWriterTest, AnExistingFileIsReplacedWhole) {
  const fs::path path = dir / "run.wav";
  write_wav(path.string(), std::vector<float>(1000, 0.1f), 48000);
  write_wav(path.string(), std::vector<float>(10, 0.2f), 48000);
  EXPECT_EQ(fs::file_size(path), 44u + 20u);
}

TEST_F(WavWriterTest, AnUnwritablePathThrowsAndLeavesNothing) {
  const fs::path path = dir / "no_such_dir" / "x.wav";
  EXPECT_THROW(write_wav(path.string(), std::vector<float>(10, 0.0f), 48000), std::runtime_error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(dir / "no_such_dir"));
}

TEST_F(WavWriterTest, AnEmptyRunIsAValidEmptyFile) {
  const fs::path path = dir / "empty.wav";
  write_wav(path.string(), {}, 48000);
  const auto b = read_bytes(path);
  ASSERT_EQ(b.size(), 44u);
  EXPECT_EQ(u32(b, 40), 0u);
  EXPECT_EQ(u32(b, 4), 36u);
}

}  // namespace
}  // namespace alloy::sound
