#include "idl/idl_text.hpp"

#include <cctype>
#include <string>

namespace teleop::idl {

namespace {

/// True when `text` has `word` at `at` as a whole word.
bool word_at(std::string_view text, std::size_t at, std::string_view word) {
  if (text.substr(at, word.size()) != word) return false;
  const auto is_ident = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
  };
  if (at > 0 && is_ident(text[at - 1])) return false;
  const std::size_t end = at + word.size();
  return end >= text.size() || !is_ident(text[end]);
}

bool defines(std::string_view text, std::string_view keyword, std::string_view name) {
  for (std::size_t at = text.find(keyword); at != std::string_view::npos;
       at = text.find(keyword, at + 1)) {
    if (!word_at(text, at, keyword)) continue;
    std::size_t p = at + keyword.size();
    while (p < text.size() && std::isspace(static_cast<unsigned char>(text[p])) != 0) ++p;
    if (word_at(text, p, name)) return true;
  }
  return false;
}

}  // namespace

std::string_view idl_text_for_type(std::string_view type_name) {
  // "a::b::Name": every module a, b must be opened in the file and Name defined as a struct
  std::string_view rest = type_name;
  std::string_view name = type_name;
  if (const auto sep = type_name.rfind("::"); sep != std::string_view::npos) {
    name = type_name.substr(sep + 2);
    rest = type_name.substr(0, sep);
  } else {
    rest = {};
  }
  if (name.empty()) return {};
  for (const IdlFile& f : idl_files()) {
    bool ok = defines(f.text, "struct", name);
    std::string_view mods = rest;
    while (ok && !mods.empty()) {
      const auto sep = mods.find("::");
      ok = defines(f.text, "module", mods.substr(0, sep));
      mods = sep == std::string_view::npos ? std::string_view{} : mods.substr(sep + 2);
    }
    if (ok) return f.text;
  }
  return {};
}

}  // namespace teleop::idl
