// A small JSON value for machine-readable records (summary.json, benchmark records).
//
// Writing only: qdemsph emits JSON and never reads it, so no JSON library is a dependency.
// Objects keep insertion order (records read top-down like the run). Doubles are written as
// the shortest text that reads back to the identical double; integers stay exact up to 2^63;
// NaN and infinities, which JSON cannot express, become null.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace qdemsph {

class Json {
 public:
  using Array = std::vector<Json>;
  using Object = std::vector<std::pair<std::string, Json>>;

  Json() = default;  // null
  Json(std::nullptr_t) {}
  Json(bool b) : v_(b) {}
  Json(double d) : v_(d) {}
  Json(float d) : v_(static_cast<double>(d)) {}
  // Any integer type other than bool: kept exact instead of converted to double.
  template <class I, std::enable_if_t<std::is_integral_v<I> && !std::is_same_v<I, bool>, int> = 0>
  Json(I i) : v_(static_cast<int64_t>(i)) {}
  Json(const char* s) : v_(std::string(s)) {}
  Json(std::string s) : v_(std::move(s)) {}
  Json(std::string_view s) : v_(std::string(s)) {}
  Json(Array a) : v_(std::move(a)) {}

  static Json array() { return Json(Array{}); }
  static Json object() {
    Json j;
    j.v_ = Object{};
    return j;
  }

  bool is_null() const { return std::holds_alternative<std::nullptr_t>(v_); }
  bool is_object() const { return std::holds_alternative<Object>(v_); }
  bool is_array() const { return std::holds_alternative<Array>(v_); }

  // Object member access; a null value becomes an empty object first, so records can be built
  // as j["timing"]["step"] = 1.5. Inserts the key at the end when absent.
  Json& operator[](std::string_view key);
  // Appends to an array; a null value becomes an empty array first. Returns the new element.
  Json& push_back(Json value);
  size_t size() const;  // elements of an array or members of an object; 0 otherwise

  // indent < 0: one line; otherwise pretty-printed with that many spaces per level.
  std::string dump(int indent = 2) const;
  // Writes dump() + "\n" to `path` atomically (see write_file_atomically).
  void write_file(const std::filesystem::path& path, int indent = 2) const;

 private:
  void dump_to(std::string& out, int indent, int depth) const;
  std::variant<std::nullptr_t, bool, int64_t, double, std::string, Array, Object> v_ = nullptr;
};

// JSON text of a string, with quotes; escapes quotes, backslashes and control characters.
std::string json_quote(std::string_view s);
// Shortest decimal text that reads back to exactly `x`; "null" when x is not finite.
std::string json_number(double x);

// --- output-file helpers shared by the writers (json, fields, probes) ---

// Creates `dir` (and parents) if needed and checks that a file can be created in it.
// Throws InputError naming the folder otherwise.
void ensure_output_dir(const std::filesystem::path& dir);
// Writes `text` to `path` so that a reader sees either the old or the new content, never a
// partial file: write PATH.tmp, flush, rename over PATH. Throws InputError on failure.
void write_file_atomically(const std::filesystem::path& path, std::string_view text);
// Continues a text output after a restart: truncates PATH to its first `bytes` bytes (what it
// held at the checkpoint) and opens it for appending. InputError when PATH is missing or
// shorter, or its first line differs from `header` (the columns changed).
std::FILE* reopen_for_append(const std::filesystem::path& path, std::int64_t bytes,
                             const std::string& header);

}  // namespace qdemsph
