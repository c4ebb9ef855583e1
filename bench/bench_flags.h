// The command lines of the benches that parse their own (the Google Benchmark ones have the
// library's): `--flag value` pairs. --help prints the bench's usage; a flag without its value, an
// argument that is no flag, or a value the flag does not take is one line naming it on stderr and
// exit status 2, before anything is timed.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

namespace sdft::bench {

// -1 when argv[1..] are flag-value pairs and none asks for help; otherwise the status to exit
// with, after the usage (stdout for --help, stderr after an error).
inline int checkFlagPairs(int argc, char** argv, const char* usage) {
    for (int i = 1; i < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            std::fputs(usage, stdout);
            return 0;
        }
        const char* why = a.rfind("--", 0) != 0 ? "is not a flag" : nullptr;
        if (!why && i + 1 >= argc) why = "needs a value";
        if (why) {
            std::fprintf(stderr, "%s: %s\n%s", a.c_str(), why, usage);
            return 2;
        }
    }
    return -1;
}

[[noreturn]] inline void badValue(const std::string& flag, const std::string& v,
                                  const std::string& wanted) {
    std::fprintf(stderr, "%s: '%s' is not %s\n", flag.c_str(), v.c_str(), wanted.c_str());
    std::exit(2);
}

// Whether all of v converts by `to` (a std::stol or std::stof call taking v and the count read).
template <class T, class To>
bool parseAll(const std::string& v, To to, T& out) {
    size_t used = 0;
    try {
        out = to(v, &used);
    } catch (const std::exception&) {
        return false;
    }
    return used != 0 && used == v.size();
}

// `flag`'s value as a whole number of at least `lo`.
inline int intFlag(const std::string& flag, const std::string& v, int lo = 1) {
    long n = 0;
    if (!parseAll(
            v, [](const std::string& s, size_t* used) { return std::stol(s, used); }, n) ||
        n < lo || n > 1 << 30)
        badValue(flag, v,
                 lo == 1 ? "a positive whole number"
                         : "a whole number of at least " + std::to_string(lo));
    return static_cast<int>(n);
}

// `flag`'s value as a finite number.
inline float floatFlag(const std::string& flag, const std::string& v) {
    float x = 0;
    if (!parseAll(
            v, [](const std::string& s, size_t* used) { return std::stof(s, used); }, x) ||
        !(x - x == 0))
        badValue(flag, v, "a number");
    return x;
}

// `flag`'s comma-separated whole numbers, each at least `lo`.
inline std::vector<int> intListFlag(const std::string& flag, const std::string& v, int lo = 1) {
    std::vector<int> out;
    std::stringstream in(v);
    for (std::string part; std::getline(in, part, ',');) out.push_back(intFlag(flag, part, lo));
    if (out.empty()) badValue(flag, v, "a list of whole numbers");
    return out;
}

// `flag`'s comma-separated numbers.
inline std::vector<float> floatListFlag(const std::string& flag, const std::string& v) {
    std::vector<float> out;
    std::stringstream in(v);
    for (std::string part; std::getline(in, part, ',');) out.push_back(floatFlag(flag, part));
    if (out.empty()) badValue(flag, v, "a list of numbers");
    return out;
}

}  // namespace sdft::bench
