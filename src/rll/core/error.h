// The one error type of rll: a message meant for the user (file, line, flag named in it).
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace rll {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <typename... Args>
[[noreturn]] inline void fail(fmt::format_string<Args...> f, Args&&... args) {
  throw Error(fmt::format(f, std::forward<Args>(args)...));
}

}  // namespace rll
