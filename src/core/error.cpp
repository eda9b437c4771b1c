#include "core/error.hpp"

#include <fmt/format.h>

namespace lamina {

std::string Diagnostic::format() const {
  std::string where = file.empty() ? std::string("<input>") : file;
  if (line > 0) where += fmt::format(":{}:{}", line, column);
  std::string text = fmt::format("{}: {}", where, key_path.empty() ? std::string("<root>") : key_path);
  if (!expected.empty()) text += fmt::format(": expected {}", expected);
  if (!found.empty()) text += fmt::format(", found {}", found);
  return text;
}

static std::string join(const std::vector<Diagnostic>& diagnostics) {
  std::string text;
  for (const auto& d : diagnostics) {
    if (!text.empty()) text += '\n';
    text += d.format();
  }
  return text;
}

InputError::InputError(std::vector<Diagnostic> diagnostics)
    : std::runtime_error(join(diagnostics)), diagnostics_(std::move(diagnostics)) {}

InputError::InputError(const std::string& key_path, const std::string& expected, const std::string& found)
    : InputError(Diagnostic{"", 0, 0, key_path, expected, found}) {}

}  // namespace lamina
