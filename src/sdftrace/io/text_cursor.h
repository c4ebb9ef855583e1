// Whitespace-separated tokens of a text file held in memory, with the line each came from, for
// the readers of text formats (mesh_readers.h): numbers parsed by std::from_chars (no locale, no
// allocation), and every failure one InputError "<path>:<line>: <what>".
#pragma once

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>

#include "sdftrace/core/error.h"

namespace sdft {

class TextCursor {
  public:
    TextCursor(const char* begin, const char* end, std::string path)
        : m_p(begin), m_end(end), m_path(std::move(path)) {}

    // Skips spaces, tabs, carriage returns and (unless `stopAtNewline`) newlines; '#' comments
    // to the end of their line where `comments`.
    void skipSpace(bool stopAtNewline = false) {
        while (m_p < m_end) {
            const char c = *m_p;
            if (c == '\n') {
                if (stopAtNewline) return;
                ++m_line;
            } else if (c == '#' && m_comments) {
                while (m_p < m_end && *m_p != '\n') ++m_p;
                continue;
            } else if (c != ' ' && c != '\t' && c != '\r' && c != '\f' && c != '\v') {
                return;
            }
            ++m_p;
        }
    }
    void allowComments(bool on) { m_comments = on; }
    bool atEnd() {
        skipSpace();
        return m_p >= m_end;
    }
    // Whether the current line has another token.
    bool moreOnLine() {
        skipSpace(true);
        return m_p < m_end && *m_p != '\n';
    }
    // The rest of the current line and past its newline.
    void skipLine() {
        while (m_p < m_end && *m_p != '\n') ++m_p;
        if (m_p < m_end) {
            ++m_p;
            ++m_line;
        }
    }
    // The next token (empty at the end of the text).
    std::string_view token() {
        skipSpace();
        const char* start = m_p;
        while (m_p < m_end && !isSpace(*m_p)) ++m_p;
        return {start, static_cast<size_t>(m_p - start)};
    }
    // The next token, left to be read again.
    std::string_view peekToken() {
        const char* p = m_p;
        const auto line = m_line;
        const std::string_view t = token();
        m_p = p;
        m_line = line;
        return t;
    }
    double number(const char* what) {
        const std::string_view t = token();
        double v = 0;
        const char* first = t.data();
        if (!t.empty() && *first == '+') ++first;  // from_chars does not take a leading '+'
        const auto [ptr, ec] = std::from_chars(first, t.data() + t.size(), v);
        if (ec == std::errc::result_out_of_range && ptr == t.data() + t.size())
            fail(std::string(what) + ": '" + printable(t.substr(0, 32)) +
                 "' is outside the range of double-precision numbers");
        if (t.empty() || ec != std::errc() || ptr != t.data() + t.size())
            fail(expected(what, t, "a number"));
        return v;
    }
    int64_t integer(const char* what) {
        const std::string_view t = token();
        int64_t v = 0;
        if (!toInteger(t, v)) fail(expected(what, t, "an integer"));
        return v;
    }
    // `t` whole as a decimal integer (a leading '+' allowed); false if it is not one.
    static bool toInteger(std::string_view t, int64_t& v) {
        const char* first = t.data();
        if (!t.empty() && *first == '+') ++first;
        const auto [ptr, ec] = std::from_chars(first, t.data() + t.size(), v);
        return !t.empty() && ec == std::errc() && ptr == t.data() + t.size();
    }
    const char* position() const { return m_p; }
    int line() const { return m_line; }
    const std::string& path() const { return m_path; }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(m_path + ":" + std::to_string(m_line) + ": " + what);
    }

  private:
    static bool isSpace(char c) {
        return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
    }
    std::string expected(const char* what, std::string_view got, const char* kind) const {
        std::string s(what);
        s += ": expected ";
        s += kind;
        s += got.empty() ? std::string(", found the end of the file (is it cut short?)")
                         : ", found '" + printable(got.substr(0, 32)) + "'";
        return s;
    }

  public:
    // `text` with bytes outside printable ASCII written as \xNN (a damaged file's bytes in an
    // error line).
    static std::string printable(std::string_view text) {
        std::string s;
        for (const char c : text) {
            const auto u = static_cast<unsigned char>(c);
            if (u >= 0x20 && u < 0x7f) {
                s += c;
            } else {
                static constexpr char kHex[] = "0123456789abcdef";
                s += "\\x";
                s += kHex[u >> 4];
                s += kHex[u & 15];
            }
        }
        return s;
    }

  private:
    const char* m_p;
    const char* m_end;
    std::string m_path;
    int m_line = 1;
    bool m_comments = false;
};

}  // namespace sdft
