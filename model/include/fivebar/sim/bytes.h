// Flat byte strings for results passed between processes of one build (fork pipes, MPI):
// trivially copyable values in their native layout, strings as a 64-bit length and the bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace fivebar::sim {

/// Appends values to a byte string.
class ByteWriter {
 public:
  template <typename T>
  void put(const T& x) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain values go into a byte string");
    bytes_.append(reinterpret_cast<const char*>(&x), sizeof(T));
  }
  void put_string(const std::string& s) {
    put(static_cast<std::int64_t>(s.size()));
    bytes_.append(s);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

/// Reads back, in the same order, what a ByteWriter wrote. `bytes` must outlive the reader.
class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}

  /// The next value into *x; false (and *x untouched) when the bytes end first.
  template <typename T>
  bool get(T* x) {
    static_assert(std::is_trivially_copyable_v<T>, "only plain values come from a byte string");
    if (pos_ + sizeof(T) > bytes_.size()) return false;
    std::memcpy(x, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool get_string(std::string* s) {
    std::int64_t n = 0;
    if (!get(&n) || n < 0 || pos_ + static_cast<std::size_t>(n) > bytes_.size()) return false;
    s->assign(bytes_, pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    return true;
  }

  /// The next value; throws std::runtime_error(what) when the bytes end first.
  template <typename T>
  T take(const char* what) {
    T x{};
    if (!get(&x)) throw std::runtime_error(what);
    return x;
  }
  std::string take_string(const char* what) {
    std::string s;
    if (!get_string(&s)) throw std::runtime_error(what);
    return s;
  }

 private:
  const std::string& bytes_;
  std::size_t pos_ = 0;
};

}  // namespace fivebar::sim
