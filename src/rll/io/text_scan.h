// Line and number scanning for the text formats rll reads (OBJ, MTL): line numbers for error
// messages, strict, correctly rounded number parsing, and file bytes made safe to print.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace rll {

// Reads a whole file; throws rll::Error naming it when it cannot be read.
std::string read_text_file(const std::filesystem::path& path);

// Bytes from a file as a message may show them (shown_text, core/params.h): UTF-8 text as it is
// (a material named "café" reads so), control characters and bytes that are not UTF-8 as \xNN
// and a backslash as \\, and at most `max_bytes` of the input ("..." marks a cut), so that an
// error neither replays a file nor drives the terminal.
std::string printable(std::string_view bytes, size_t max_bytes = 48);
// A whole message with only its control bytes (C0, DEL) written as \xNN: text that is already
// quoted with printable() stays as it is, and so do UTF-8 file names.
std::string without_control_bytes(std::string_view message);

// Why a referenced file cannot be read, for "'NAME' " + this: "is a folder, not a file", "is not
// a regular file" (a device or pipe), "not found", or "" when it is a regular file.
std::string unreadable_reason(const std::filesystem::path& path);

// The lines of a text as tinyobjloader splits them: "\n", "\r\n" and a lone "\r" end a line.
class TextLines {
 public:
  explicit TextLines(std::string_view text) : m_text(text) {}
  // The next line without its ending; false at the end of the text.
  bool next(std::string_view& line);
  // 1-based number of the line last returned by next().
  size_t number() const { return m_number; }

 private:
  std::string_view m_text;
  size_t m_pos = 0, m_number = 0;
};

// Splits off the next token separated by spaces or tabs; false when none is left.
bool next_token(std::string_view& rest, std::string_view& token);

enum class NumberStatus { Ok, Malformed, NonFinite };
// Parses all of `s` as a decimal float (an optional leading '+' allowed), correctly rounded;
// values too small for a float become 0, too large ones are NonFinite, as are nan and inf.
NumberStatus parse_float(std::string_view s, float& out);
// Parses all of `s` as a decimal integer (an optional leading '+' allowed).
bool parse_long(std::string_view s, long& out);

}  // namespace rll
