// The bytes a stage saves of its own state (Stage::save_state) and reads back
// (Stage::restore_state), for snapshots, saves and state hashes.
//
// The format is the stage's own business: the world stores the bytes as they
// are, hashes them, and hands them back to a fresh instance of the same stage.
// Numbers go in as their exact bits (host byte order: little endian on every
// platform alloy builds for), so that a restored double is the same double.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "runtime/error.hpp"

namespace alloy {

/// Collects a stage's state as bytes.
class StateWriter {
 public:
  /// A trivially copyable value (a number, an id, a Vec3), bit for bit.
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>, "put() takes plain values; use put_string");
    const auto* p = reinterpret_cast<const std::byte*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  /// A length (64-bit) and the characters.
  void put_string(std::string_view s) {
    put<std::uint64_t>(s.size());
    const auto* p = reinterpret_cast<const std::byte*>(s.data());
    bytes_.insert(bytes_.end(), p, p + s.size());
  }
  /// A count (64-bit) and the values, for a vector of plain values.
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(v.size());
    const auto* p = reinterpret_cast<const std::byte*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  const std::vector<std::byte>& bytes() const { return bytes_; }
  std::vector<std::byte> take() { return std::move(bytes_); }

 private:
  std::vector<std::byte> bytes_;
};

/// Reads back what a StateWriter wrote, in the same order. Reading past the
/// end, or an absurd count, throws InputError naming the stage: a snapshot
/// from another version of the stage must fail loudly, never read garbage.
class StateReader {
 public:
  StateReader(std::string stage, const std::vector<std::byte>& bytes)
      : stage_(std::move(stage)), bytes_(bytes) {}

  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    need(n);
    std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), std::size_t(n));
    at_ += std::size_t(n);
    return s;
  }
  template <class T>
  std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(T))
      fail("a count of " + std::to_string(n) + " is past the end");
    std::vector<T> v(static_cast<std::size_t>(n));
    // An empty vector's data() may be null, and memcpy from or to null is
    // undefined even for 0 bytes (UBSan reports it).
    if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, std::size_t(n) * sizeof(T));
    at_ += std::size_t(n) * sizeof(T);
    return v;
  }
  /// Bytes not read yet; the world requires 0 after restore_state.
  std::size_t remaining() const { return bytes_.size() - at_; }
  const std::string& stage() const { return stage_; }

 private:
  void need(std::uint64_t n) {
    if (n > bytes_.size() - at_)
      fail("needs " + std::to_string(n) + " more bytes, " + std::to_string(bytes_.size() - at_) +
           " left");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError("the saved state of stage '" + stage_ +
                     "' is damaged or from another version: " + what);
  }
  std::string stage_;
  const std::vector<std::byte>& bytes_;
  std::size_t at_ = 0;
};

}  // namespace alloy
