// Message: a fixed-size text the driver's loop writes and copies without allocating (fault reasons,
// request results, gait names). Real-time safety: every function here is noexcept and allocation-free.
#pragma once

#include <array>
#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace snake_autonomy::driver {

using Message = std::array<char, 256>;

inline void copy_message(Message& out, const char* text) noexcept { std::snprintf(out.data(), out.size(), "%s", text); }

// Appends printf-style to `out` (truncated at its size).
inline void append(Message& out, const char* fmt, ...) noexcept __attribute__((format(printf, 2, 3)));
inline void append(Message& out, const char* fmt, ...) noexcept {
  const std::size_t used = std::strlen(out.data());
  if (used + 1 >= out.size()) return;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(out.data() + used, out.size() - used, fmt, args);
  va_end(args);
}

}  // namespace snake_autonomy::driver
