// The names users see for the values of an enum (CLI options, JSON and CSV fields): one table
// per enum, read both ways, instead of a switch to name it and an if-chain to parse it.
#pragma once

#include <cstddef>
#include <string>

namespace fivebar {

/// One value of an enum and its name. A table may name a value twice (an accepted alias):
/// the first entry is the name written.
template <class E>
struct Named {
  E value;
  const char* name;
};

/// The first name of `value` in `table`, `fallback` if it has none.
template <class E, std::size_t N>
constexpr const char* name_in(const Named<E> (&table)[N], E value, const char* fallback = "unknown") {
  for (const Named<E>& entry : table) {
    if (entry.value == value) return entry.name;
  }
  return fallback;
}

/// The value named `name` in `table` into `*out`; false (and `*out` untouched) if none is.
template <class E, std::size_t N>
bool parse_in(const Named<E> (&table)[N], const std::string& name, E* out) {
  for (const Named<E>& entry : table) {
    if (name == entry.name) {
      *out = entry.value;
      return true;
    }
  }
  return false;
}

}  // namespace fivebar
