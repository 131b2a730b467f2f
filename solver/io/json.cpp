// JSON writer and the atomic-file helpers (see json.hpp).
#include "io/json.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <system_error>

#include "core/error.hpp"

namespace qdemsph {

Json& Json::operator[](std::string_view key) {
  if (is_null()) v_ = Object{};
  auto* obj = std::get_if<Object>(&v_);
  if (!obj) throw std::logic_error("Json: operator[] on a value that is not an object");
  for (auto& [k, v] : *obj)
    if (k == key) return v;
  obj->emplace_back(std::string(key), Json());
  return obj->back().second;
}

Json& Json::push_back(Json value) {
  if (is_null()) v_ = Array{};
  auto* arr = std::get_if<Array>(&v_);
  if (!arr) throw std::logic_error("Json: push_back on a value that is not an array");
  arr->push_back(std::move(value));
  return arr->back();
}

size_t Json::size() const {
  if (const auto* a = std::get_if<Array>(&v_)) return a->size();
  if (const auto* o = std::get_if<Object>(&v_)) return o->size();
  return 0;
}

std::string json_quote(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out += '"';
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\b':
        out += "\\b";
        break;
      case '\f':
        out += "\\f";
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
        // Other control characters must be \u-escaped; bytes >= 0x80 pass through as UTF-8.
        if (c < 0x20)
          out += fmt::format("\\u{:04x}", c);
        else
          out += ch;
    }
  }
  out += '"';
  return out;
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  // fmt's default double format is the shortest text that round-trips (Ryu-like), which
  // also reads well (0.1, not 0.10000000000000001). It can print "1e+20", valid JSON.
  std::string s = fmt::format("{}", x);
  return s;
}

void Json::dump_to(std::string& out, int indent, int depth) const {
  const auto newline = [&](int d) {
    if (indent < 0) return;
    out += '\n';
    out.append(static_cast<size_t>(indent * d), ' ');
  };
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::nullptr_t>)
          out += "null";
        else if constexpr (std::is_same_v<T, bool>)
          out += v ? "true" : "false";
        else if constexpr (std::is_same_v<T, int64_t>)
          out += std::to_string(v);
        else if constexpr (std::is_same_v<T, double>)
          out += json_number(v);
        else if constexpr (std::is_same_v<T, std::string>)
          out += json_quote(v);
        else if constexpr (std::is_same_v<T, Array>) {
          if (v.empty()) return void(out += "[]");
          out += '[';
          for (size_t i = 0; i < v.size(); ++i) {
            if (i) out += ',';
            newline(depth + 1);
            v[i].dump_to(out, indent, depth + 1);
          }
          newline(depth);
          out += ']';
        } else {
          if (v.empty()) return void(out += "{}");
          out += '{';
          for (size_t i = 0; i < v.size(); ++i) {
            if (i) out += ',';
            newline(depth + 1);
            out += json_quote(v[i].first);
            out += indent < 0 ? ":" : ": ";
            v[i].second.dump_to(out, indent, depth + 1);
          }
          newline(depth);
          out += '}';
        }
      },
      v_);
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  return out;
}

void Json::write_file(const std::filesystem::path& path, int indent) const {
  write_file_atomically(path, dump(indent) + "\n");
}

void ensure_output_dir(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError("output folder '" + dir.string() +
                     "' cannot be created: " + (ec ? ec.message() : "a file of that name exists"));
  // Permission bits do not tell the whole story (read-only mounts, root, ACLs): try it.
  const fs::path probe = dir / ".qdemsph-write-test";
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw InputError("output folder '" + dir.string() + "' is not writable");
  std::fclose(f);
  fs::remove(probe, ec);
}

void write_file_atomically(const std::filesystem::path& path, std::string_view text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throw InputError("cannot write '" + tmp.string() + "': folder not writable");
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  if (std::fclose(f) != 0 || !ok) {
    std::remove(tmp.c_str());
    throw InputError("cannot write '" + tmp.string() + "' (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);  // atomic on POSIX within one file system
  if (ec)
    throw InputError("cannot rename '" + tmp.string() + "' to '" + path.string() +
                     "': " + ec.message());
}

std::FILE* reopen_for_append(const std::filesystem::path& path, std::int64_t bytes,
                             const std::string& header) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec || static_cast<std::int64_t>(size) < bytes)
    throw InputError(
        "cannot continue '" + path.string() + "': " +
        (ec ? "missing" : "shorter than at the checkpoint (" + std::to_string(bytes) + " bytes)"));
  std::FILE* f = std::fopen(path.c_str(), "r+");
  if (!f) throw InputError("cannot continue '" + path.string() + "': not writable");
  std::string first(header.size(), '\0');
  const bool same = std::fread(first.data(), 1, first.size(), f) == first.size() && first == header;
  std::fclose(f);
  if (!same)
    throw InputError("cannot continue '" + path.string() +
                     "': its columns differ from this scene's (probes changed?)");
  fs::resize_file(path, static_cast<std::uintmax_t>(bytes), ec);
  if (ec) throw InputError("cannot truncate '" + path.string() + "': " + ec.message());
  f = std::fopen(path.c_str(), "a");
  if (!f) throw InputError("cannot continue '" + path.string() + "': not writable");
  std::fseek(f, 0, SEEK_END);  // so that ftell reports the length before the first write
  return f;
}

}  // namespace qdemsph
