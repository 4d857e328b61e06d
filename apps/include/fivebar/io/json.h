// A small JSON value for run summaries (summary.json, identification.json): objects keep their
// keys in insertion order; numbers are written in shortest round-trip form, non-finite ones as
// null (JSON has no NaN).
#pragma once

#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace fivebar::io {

class Json {
 public:
  enum class Type { kNull, kBool, kNumber, kInteger, kString, kArray, kObject };

  Json() = default;  ///< null
  Json(bool b) : type_(Type::kBool), bool_(b) {}
  Json(double x) : type_(Type::kNumber), number_(x) {}
  Json(int i) : type_(Type::kInteger), integer_(i) {}
  Json(long i) : type_(Type::kInteger), integer_(i) {}
  Json(long long i) : type_(Type::kInteger), integer_(i) {}
  Json(unsigned long i) : type_(Type::kInteger), integer_(static_cast<long long>(i)) {}
  Json(std::string s) : type_(Type::kString), string_(std::move(s)) {}
  Json(const char* s) : type_(Type::kString), string_(s) {}

  static Json object() { return Json(Type::kObject); }
  /// An object with these members, in order: Json::object({{"line", 12}, {"value", 0.5}}).
  static Json object(std::initializer_list<std::pair<std::string, Json>> members) {
    Json o = object();
    o.set(members);
    return o;
  }
  static Json array() { return Json(Type::kArray); }
  /// An array of the elements of `range` (numbers or strings), in order.
  template <class Range>
  static Json array_of(const Range& range) {
    Json a = array();
    for (const auto& v : range) a.push(Json(v));
    return a;
  }
  /// An array of to_json(element) for the elements of `range`, in order.
  template <class Range, class ToJson>
  static Json array_of(const Range& range, ToJson to_json) {
    Json a = array();
    for (const auto& v : range) a.push(to_json(v));
    return a;
  }

  /// Object: sets `key` (replacing an existing one in place). Returns *this for chaining.
  Json& set(const std::string& key, Json value);
  /// Object: sets these members in order, as set(key, value) each.
  Json& set(std::initializer_list<std::pair<std::string, Json>> members) {
    for (const auto& [key, value] : members) set(key, value);
    return *this;
  }
  /// Object: the member `key`, created as null when absent.
  Json& operator[](const std::string& key);
  /// Array: appends `value`.
  Json& push(Json value);

  Type type() const { return type_; }
  /// Readers of each type (for the Python module, which turns a record into Python objects):
  /// the value of a bool, a number (an integer as double), an integer or a string.
  bool boolean() const { return bool_; }
  double number() const { return type_ == Type::kInteger ? double(integer_) : number_; }
  long long integer() const { return integer_; }
  const std::string& string() const { return string_; }
  /// Object: member names, parallel to items(). Array: empty.
  const std::vector<std::string>& keys() const { return keys_; }
  /// Array elements, or object member values.
  const std::vector<Json>& items() const { return items_; }
  /// Text with `indent` spaces per level; 0 writes one line.
  std::string dump(int indent = 2) const;

 private:
  explicit Json(Type t) : type_(t) {}
  void dump(std::string* out, int indent, int depth) const;

  Type type_ = Type::kNull;
  bool bool_ = false;
  double number_ = 0;
  long long integer_ = 0;
  std::string string_;
  std::vector<std::string> keys_;  // object member names, parallel to items_
  std::vector<Json> items_;        // array elements or object member values
};

/// `s` as a JSON string literal, quotes included.
std::string json_quote(const std::string& s);

}  // namespace fivebar::io
