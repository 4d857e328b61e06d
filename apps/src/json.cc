#include "fivebar/io/json.h"

#include <cmath>
#include <cstdio>

#include "fivebar/io/format.h"

namespace fivebar::io {

Json& Json::set(const std::string& key, Json value) {
  (*this)[key] = std::move(value);
  return *this;
}

Json& Json::operator[](const std::string& key) {
  if (type_ == Type::kNull) type_ = Type::kObject;
  for (size_t i = 0; i < keys_.size(); ++i) {
    if (keys_[i] == key) return items_[i];
  }
  keys_.push_back(key);
  items_.emplace_back();
  return items_.back();
}

Json& Json::push(Json value) {
  if (type_ == Type::kNull) type_ = Type::kArray;
  items_.push_back(std::move(value));
  return *this;
}

std::string Json::dump(int indent) const {
  std::string out;
  dump(&out, indent, 0);
  return out;
}

void Json::dump(std::string* out, int indent, int depth) const {
  // line break and indentation before a member at `level`
  auto newline = [&](int level) {
    if (indent > 0) *out += "\n" + std::string(static_cast<size_t>(indent * level), ' ');
  };
  switch (type_) {
    case Type::kNull:
      *out += "null";
      return;
    case Type::kBool:
      *out += bool_ ? "true" : "false";
      return;
    case Type::kNumber:
      *out += std::isfinite(number_) ? format_double(number_) : "null";
      return;
    case Type::kInteger:
      *out += std::to_string(integer_);
      return;
    case Type::kString:
      *out += json_quote(string_);
      return;
    case Type::kArray:
    case Type::kObject: {
      const bool object = type_ == Type::kObject;
      *out += object ? "{" : "[";
      for (size_t i = 0; i < items_.size(); ++i) {
        if (i) *out += indent > 0 ? "," : ", ";
        newline(depth + 1);
        if (object) *out += json_quote(keys_[i]) + ": ";
        items_[i].dump(out, indent, depth + 1);
      }
      if (!items_.empty()) newline(depth);
      *out += object ? "}" : "]";
      return;
    }
  }
}

std::string json_quote(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (c < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += static_cast<char>(c);
        }
    }
  }
  return out + "\"";
}

}  // namespace fivebar::io
