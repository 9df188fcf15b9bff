// Little binary files rll writes for itself (learnt sampler states): values appended to a byte
// string, and read back with every read bounds-checked, so that a truncated or damaged file is
// an rll::Error naming the file, never a read past the end.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include "rll/core/error.h"

namespace rll {

class BinaryWriter {
 public:
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    m_bytes.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  template <typename T>
  void put_array(const T* p, size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    m_bytes.append(reinterpret_cast<const char*>(p), n * sizeof(T));
  }
  void put_string(const std::string& s) {
    put(uint64_t(s.size()));
    m_bytes.append(s);
  }
  const std::string& bytes() const { return m_bytes; }
  std::string& bytes() { return m_bytes; }

 private:
  std::string m_bytes;
};

class BinaryReader {
 public:
  // `name` is the file, for messages; `bytes` must outlive the reader.
  BinaryReader(const std::string& bytes, std::string name, size_t begin = 0, size_t end = std::string::npos)
      : m_bytes(bytes), m_name(std::move(name)), m_pos(begin), m_end(std::min(end, bytes.size())) {}
  template <typename T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    std::memcpy(&v, take(sizeof(T)), sizeof(T));
    return v;
  }
  template <typename T>
  void get_array(T* p, size_t n) {
    static_assert(std::is_trivially_copyable_v<T>);
    if (n > remaining() / sizeof(T)) truncated();
    std::memcpy(p, take(n * sizeof(T)), n * sizeof(T));
  }
  std::string get_string() {
    const uint64_t n = get<uint64_t>();
    if (n > remaining()) truncated();
    return std::string(take(size_t(n)), size_t(n));
  }
  size_t remaining() const { return m_end - m_pos; }
  size_t position() const { return m_pos; }
  const std::string& name() const { return m_name; }
  [[noreturn]] void truncated() const {
    fail("cannot read '{}': the file is truncated (it ends at byte {} of what it claims)", m_name,
         m_bytes.size());
  }

 private:
  const char* take(size_t n) {
    if (n > remaining()) truncated();
    const char* p = m_bytes.data() + m_pos;
    m_pos += n;
    return p;
  }
  const std::string& m_bytes;
  std::string m_name;
  size_t m_pos, m_end;
};

}  // namespace rll
