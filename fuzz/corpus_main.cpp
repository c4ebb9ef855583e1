// Runs a fuzz target without libFuzzer, with any compiler: how the corpora run as ordinary tests,
// and the fuzz smoke that every test run (and CI) does.
//
//   fuzz_corpus_T PATH...                         each file (directories recursively) once
//   fuzz_corpus_T --mutate SECONDS [--seed N] [--dict FILE] PATH...
//                                                 the files once, then mutants of them for SECONDS
//
// Mutants are made as libFuzzer makes them, without coverage feedback: bits flipped, bytes set to
// interesting values, ranges erased, repeated or copied, integers of every width written at random
// offsets, decimal numbers in text replaced, dictionary tokens inserted, two inputs spliced, the
// input cut short; one to five of these stacked. The corpus holds the inputs a coverage-guided
// campaign found (scripts/fuzz.sh), so mutants of them reach deep into the readers quickly.
// A crash, an abort (an exception other than the target's InputError escaping) or an input that
// runs over 20 s writes the input to fuzz-smoke-<target>-<pid>.bin in the working directory and
// names it; the exit is then non-zero. Under the sanitizer build (make test-sanitize) a memory
// error is a crash too.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#if defined(__SANITIZE_ADDRESS__)
#define SDFT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SDFT_ASAN 1
#endif
#endif
#if SDFT_ASAN
#include <sanitizer/common_interface_defs.h>
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

using Bytes = std::vector<uint8_t>;

Bytes readFile(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The input being run, for the signal handler: saved where a crash or a timeout can write it.
const uint8_t* g_current = nullptr;
size_t g_currentSize = 0;
char g_artifact[512] = "";

void writeAll(int fd, const void* data, size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = write(fd, p, size);
        if (n <= 0) return;
        p += n;
        size -= static_cast<size_t>(n);
    }
}

void message(const char* text) { writeAll(2, text, std::strlen(text)); }

// Async-signal-safe: says what happened and saves the input.
void saveInput(const char* what) {
    message(what);
    if (g_current && g_artifact[0]) {
        const int fd = open(g_artifact, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            writeAll(fd, g_current, g_currentSize);
            close(fd);
            message("; it is saved as ");
            message(g_artifact);
        }
    }
    message("\n");
}

extern "C" void onFatalSignal(int sig) {
    saveInput(sig == SIGALRM ? "fuzz smoke: an input ran over 20 s"
                             : "fuzz smoke: an input crashed");
    signal(sig == SIGALRM ? SIGABRT : sig, SIG_DFL);
    raise(sig == SIGALRM ? SIGABRT : sig);
}

#if SDFT_ASAN
// assimp keeps memory on some of its error paths (damaged glTF files in the mesh_anim and
// mesh_gltf corpora): a dependency's leak, not sdftrace's, and not a crash. LeakSanitizer still
// checks everything else the corpora run.
extern "C" const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }

// The sanitizers report memory errors (and segmentation faults, with a stack) themselves, then
// call this before the process ends.
extern "C" void onSanitizerDeath() { saveInput("fuzz smoke: the sanitizer stopped an input"); }
#endif

void run(const Bytes& input) {
    g_current = input.data();
    g_currentSize = input.size();
    alarm(20);
    LLVMFuzzerTestOneInput(input.data(), input.size());
    alarm(0);
}

// libFuzzer's dictionary format: one token a line, `name="value"` or `"value"`, with \\, \" and
// \xNN escapes; # starts a comment.
std::vector<Bytes> readDictionary(const std::string& path) {
    std::vector<Bytes> tokens;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        const size_t open = line.find('"'), close = line.rfind('"');
        if (line.empty() || line[0] == '#' || open == std::string::npos || close <= open) continue;
        Bytes token;
        for (size_t i = open + 1; i < close; ++i) {
            if (line[i] != '\\' || i + 1 >= close) {
                token.push_back(static_cast<uint8_t>(line[i]));
            } else if (line[i + 1] == 'x' && i + 3 < close) {
                token.push_back(
                    static_cast<uint8_t>(std::strtoul(line.substr(i + 2, 2).c_str(), nullptr, 16)));
                i += 3;
            } else {
                token.push_back(static_cast<uint8_t>(line[++i]));
            }
        }
        if (!token.empty()) tokens.push_back(std::move(token));
    }
    return tokens;
}

class Mutator {
  public:
    Mutator(const std::vector<Bytes>& corpus, std::vector<Bytes> dictionary, uint64_t seed)
        : m_corpus(corpus), m_dictionary(std::move(dictionary)), m_rng(seed) {
        for (const Bytes& b : corpus) m_maxSize = std::max(m_maxSize, 2 * b.size());
    }

    Bytes mutant() {
        Bytes b = m_corpus[pick(m_corpus.size())];
        const int steps = 1 + static_cast<int>(pick(5));
        for (int s = 0; s < steps; ++s) mutate(b);
        if (b.size() > m_maxSize) b.resize(m_maxSize);
        return b;
    }

  private:
    size_t pick(size_t n) { return n ? std::uniform_int_distribution<size_t>(0, n - 1)(m_rng) : 0; }

    void mutate(Bytes& b) {
        switch (pick(10)) {
            case 0:  // a bit
                if (!b.empty()) b[pick(b.size())] ^= static_cast<uint8_t>(1u << pick(8));
                break;
            case 1: {  // a byte: random or interesting
                static const uint8_t kBytes[] = {0,   1,   0x7f, 0x80, 0xff, '0',
                                                 '9', '-', '.',  ' ',  '\n'};
                if (b.empty()) break;
                b[pick(b.size())] =
                    pick(2) ? static_cast<uint8_t>(pick(256)) : kBytes[pick(sizeof(kBytes))];
                break;
            }
            case 2: {  // erase a range
                if (b.empty()) break;
                const size_t at = pick(b.size()), n = 1 + pick(std::min<size_t>(b.size() - at, 64));
                b.erase(b.begin() + static_cast<ptrdiff_t>(at),
                        b.begin() + static_cast<ptrdiff_t>(at + n));
                break;
            }
            case 3: {  // repeat a range, or copy it over another place
                if (b.empty()) break;
                const size_t from = pick(b.size()),
                             n = 1 + pick(std::min<size_t>(b.size() - from, 64));
                const Bytes chunk(b.begin() + static_cast<ptrdiff_t>(from),
                                  b.begin() + static_cast<ptrdiff_t>(from + n));
                const size_t to = pick(b.size());
                if (pick(2))
                    b.insert(b.begin() + static_cast<ptrdiff_t>(to), chunk.begin(), chunk.end());
                else
                    std::copy_n(chunk.begin(), std::min(n, b.size() - to),
                                b.begin() + static_cast<ptrdiff_t>(to));
                break;
            }
            case 4:  // an integer of 1, 2, 4 or 8 bytes, either byte order
                writeInteger(b);
                break;
            case 5:  // a decimal number in text replaced
                replaceNumber(b);
                break;
            case 6: {  // a dictionary token, inserted or written over
                if (m_dictionary.empty()) break;
                const Bytes& t = m_dictionary[pick(m_dictionary.size())];
                const size_t at = pick(b.size() + 1);
                if (pick(2) || at + t.size() > b.size())
                    b.insert(b.begin() + static_cast<ptrdiff_t>(at), t.begin(), t.end());
                else
                    std::copy(t.begin(), t.end(), b.begin() + static_cast<ptrdiff_t>(at));
                break;
            }
            case 7: {  // spliced with another input
                const Bytes& other = m_corpus[pick(m_corpus.size())];
                if (other.empty()) break;
                const size_t keep = pick(b.size() + 1), from = pick(other.size());
                b.resize(keep);
                b.insert(b.end(), other.begin() + static_cast<ptrdiff_t>(from), other.end());
                break;
            }
            case 8:  // cut short
                b.resize(pick(b.size() + 1));
                break;
            default: {  // random bytes inserted
                const size_t at = pick(b.size() + 1), n = 1 + pick(16);
                Bytes r(n);
                for (uint8_t& c : r) c = static_cast<uint8_t>(pick(256));
                b.insert(b.begin() + static_cast<ptrdiff_t>(at), r.begin(), r.end());
                break;
            }
        }
    }

    void writeInteger(Bytes& b) {
        static const int64_t kValues[] = {0,
                                          1,
                                          -1,
                                          2,
                                          3,
                                          8,
                                          16,
                                          255,
                                          256,
                                          0x7fff,
                                          0xffff,
                                          0x10000,
                                          0x7fffffff,
                                          INT64_C(0x80000000),
                                          INT64_C(0xffffffff),
                                          INT64_MAX,
                                          INT64_MIN};
        const size_t width = size_t{1} << pick(4);
        if (b.size() < width) return;
        int64_t v = kValues[pick(sizeof(kValues) / sizeof(kValues[0]))];
        if (pick(4) == 0) v = static_cast<int64_t>(b.size()) + static_cast<int64_t>(pick(5)) - 2;
        uint8_t bytes[8];
        std::memcpy(bytes, &v, 8);
        if (pick(2)) std::reverse(bytes, bytes + width);
        std::memcpy(b.data() + pick(b.size() - width + 1), bytes, width);
    }

    void replaceNumber(Bytes& b) {
        if (b.empty()) return;
        size_t at = pick(b.size());
        while (at < b.size() && !(b[at] >= '0' && b[at] <= '9')) ++at;
        if (at == b.size()) return;
        size_t end = at;
        while (end < b.size() && b[end] >= '0' && b[end] <= '9') ++end;
        static const char* kNumbers[] = {
            "0",    "1",   "-1",  "4294967295",           "4294967296", "2147483648",
            "1e39", "nan", "inf", "99999999999999999999", "3"};
        const std::string n = pick(3) ? std::to_string(pick(1000))
                                      : kNumbers[pick(sizeof(kNumbers) / sizeof(kNumbers[0]))];
        b.erase(b.begin() + static_cast<ptrdiff_t>(at), b.begin() + static_cast<ptrdiff_t>(end));
        b.insert(b.begin() + static_cast<ptrdiff_t>(at), n.begin(), n.end());
    }

    const std::vector<Bytes>& m_corpus;
    std::vector<Bytes> m_dictionary;
    std::mt19937_64 m_rng;
    size_t m_maxSize = 4096;
};

int usage() {
    std::fprintf(stderr,
                 "usage: fuzz_corpus_TARGET [--mutate SECONDS] [--seed N] [--dict FILE] PATH...\n");
    return 2;
}

}  // namespace

int main(int argc, char** argv) {
    double seconds = 0;
    uint64_t seed = 1;
    std::string dict;
    std::vector<std::filesystem::path> roots;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if ((a == "--mutate" || a == "--seed" || a == "--dict") && i + 1 >= argc) return usage();
        if (a == "--mutate")
            seconds = std::atof(argv[++i]);
        else if (a == "--seed")
            seed = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dict")
            dict = argv[++i];
        else if (a.rfind("--", 0) == 0)
            return usage();
        else
            roots.emplace_back(a);
    }
    std::vector<Bytes> corpus;
    for (const auto& root : roots) {
        if (std::filesystem::is_directory(root)) {
            std::vector<std::filesystem::path> files;
            for (const auto& e : std::filesystem::recursive_directory_iterator(root))
                if (e.is_regular_file()) files.push_back(e.path());
            std::sort(files.begin(), files.end());  // the same order, so the same mutants
            for (const auto& f : files) corpus.push_back(readFile(f));
        } else if (std::filesystem::exists(root)) {
            corpus.push_back(readFile(root));
        } else {
            std::fprintf(stderr, "%s: no such file or directory\n", root.c_str());
            return 2;
        }
    }
    if (corpus.empty()) return usage();
    const std::string target = std::filesystem::path(argv[0]).filename().string();
    std::snprintf(g_artifact, sizeof g_artifact, "%s/fuzz-smoke-%s-%d.bin",
                  std::filesystem::current_path().c_str(), target.c_str(), getpid());
#if SDFT_ASAN
    __sanitizer_set_death_callback(onSanitizerDeath);
    for (int sig : {SIGABRT, SIGALRM}) signal(sig, onFatalSignal);
#else
    for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM}) signal(sig, onFatalSignal);
#endif

    for (const Bytes& input : corpus) run(input);
    long mutants = 0;
    if (seconds > 0) {
        Mutator mutator(corpus, dict.empty() ? std::vector<Bytes>{} : readDictionary(dict), seed);
        const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
        while (std::chrono::steady_clock::now() < end) {
            run(mutator.mutant());
            ++mutants;
        }
    }
    std::printf("%zu inputs and %ld mutants (seed %llu) ran without a finding\n", corpus.size(),
                mutants, static_cast<unsigned long long>(seed));
    std::fflush(stdout);
    // Mutants may take the error paths of third-party readers that keep memory (assimp, OpenVDB's
    // registries): leaks are not what the smoke looks for (the campaigns run with detect_leaks=0
    // too), so it ends without LeakSanitizer's exit check. The corpus alone keeps that check.
    if (seconds > 0) _exit(0);
    return 0;
}
