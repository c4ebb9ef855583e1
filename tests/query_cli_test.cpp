// sdftrace query: exact answers on a cube through every file format, and bad input refused with
// one line, exit 1 and no output file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "cli_runner.h"

namespace sdft::e2e {
namespace {

// A cube from -1 to 1 as an OBJ (quads, outward).
const char* kCube =
    "v -1 -1 -1\nv 1 -1 -1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\n"
    "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";

double cubeSdf(double x, double y, double z) {
    const double q[3] = {std::fabs(x) - 1, std::fabs(y) - 1, std::fabs(z) - 1};
    double out = 0, in = std::max({q[0], q[1], q[2]});
    for (double v : q) out += std::max(v, 0.0) * std::max(v, 0.0);
    return std::sqrt(out) + std::min(in, 0.0);
}

// An N x 3 float32 .npy file (version 1.0, C order).
std::string npy(const std::vector<float>& xyz, const std::string& descr = "<f4", size_t cols = 3) {
    std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" +
                       std::to_string(xyz.size() / cols) + ", " + std::to_string(cols) + "), }";
    while ((10 + dict.size() + 1) % 64) dict += ' ';
    dict += '\n';
    std::string out = "\x93NUMPY\x01";
    out += '\0';
    out += static_cast<char>(dict.size() & 0xFF);
    out += static_cast<char>(dict.size() >> 8);
    out += dict;
    out.append(reinterpret_cast<const char*>(xyz.data()), xyz.size() * 4);
    return out;
}

std::vector<float> grid3(int n, float extent) {
    std::vector<float> p;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k)
                for (int a : {i, j, k}) p.push_back(-extent + 2 * extent * (a + 0.37f) / n);
    return p;
}

TEST(QueryCli, SignedDistancesOfACubeAreExactInEveryFormat) {
    TempDir dir;
    const std::string mesh = dir.write("cube.obj", kCube);
    const std::vector<float> p = grid3(9, 2.0f);
    dir.write("p.npy", npy(p));
    RunResult r =
        runCli("query -q " + mesh + " " + dir.file("p.npy") + " -o " + dir.file("d.npy"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string out = readFile(dir.file("d.npy"));
    ASSERT_NE(out.find("'descr': '<f4'"), std::string::npos);
    ASSERT_NE(out.find("'shape': (729,)"), std::string::npos);
    const size_t n = p.size() / 3;
    ASSERT_EQ(out.size() % 64, (n * 4) % 64);  // header padded to 64 bytes
    std::vector<float> d(n);
    std::memcpy(d.data(), out.data() + out.size() - n * 4, n * 4);
    for (size_t i = 0; i < n; ++i)
        ASSERT_NEAR(d[i], cubeSdf(p[3 * i], p[3 * i + 1], p[3 * i + 2]), 1e-6) << i;

    // CSV in (float64), CSV out, every sign rule.
    std::ostringstream csv;
    csv.precision(9);  // every float exactly
    csv << "x,y,z\n# a comment\n";
    for (size_t i = 0; i < 50; ++i)
        csv << p[3 * i] << "," << p[3 * i + 1] << "," << p[3 * i + 2] << "\n";
    dir.write("p.csv", csv.str());
    for (const char* sign : {"winding", "parity", "pseudonormal"}) {
        r = runCli(std::string("query -q --sign ") + sign + " " + mesh + " " + dir.file("p.csv") +
                       " -o " + dir.file("d.csv"),
                   dir);
        ASSERT_EQ(r.status, 0) << r.err;
        std::istringstream back(readFile(dir.file("d.csv")));
        std::string line;
        std::getline(back, line);
        EXPECT_EQ(line, "sdf");
        for (size_t i = 0; i < 50; ++i) {
            ASSERT_TRUE(std::getline(back, line));
            EXPECT_NEAR(std::stod(line), cubeSdf(p[3 * i], p[3 * i + 1], p[3 * i + 2]), 1e-6)
                << sign << " " << i;
        }
    }
    EXPECT_NE(r.err.find("-> " + dir.file("d.csv") + ": 50 points"), std::string::npos) << r.err;
}

TEST(QueryCli, SamplesAndRaysWriteNamedArrays) {
    TempDir dir;
    const std::string mesh = dir.write("cube.obj", kCube);
    RunResult r = runCli(
        "query -q " + mesh + " --sample surface --count 500 --seed 3 -o " + dir.file("s.npz"), dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string npz = readFile(dir.file("s.npz"));
    for (const char* name : {"points.npy", "normal.npy", "face.npy", "sdf.npy"})
        EXPECT_NE(npz.find(name), std::string::npos) << name;
    EXPECT_EQ(npz.substr(0, 4), std::string("PK\x03\x04", 4));
    // The same seed, the same file.
    r = runCli(
        "query -q " + mesh + " --sample surface --count 500 --seed 3 -o " + dir.file("s2.npz"),
        dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readFile(dir.file("s2.npz")), npz);
    dir.write("o.npy", npy({0, 0, 0, 3, 0, 0, 3, 3, 0}));
    dir.write("d.npy", npy({1, 0, 0, -1, 0, 0, 0, 0, 1}));
    r = runCli("query -q " + mesh + " " + dir.file("o.npy") + " --rays " + dir.file("d.npy") +
                   " -o " + dir.file("r.csv"),
               dir);
    ASSERT_EQ(r.status, 0) << r.err;
    std::istringstream back(readFile(dir.file("r.csv")));
    std::string line;
    std::getline(back, line);
    EXPECT_EQ(line, "t,face,barycentric_x,barycentric_y,normal_x,normal_y,normal_z");
    std::getline(back, line);
    EXPECT_EQ(line.substr(0, 2), "1,");
    std::getline(back, line);
    EXPECT_EQ(line.substr(0, 2), "2,");
    std::getline(back, line);
    EXPECT_EQ(line.substr(0, 6), "inf,-1");
}

TEST(QueryCli, BadInputIsOneLineAndNoOutput) {
    TempDir dir;
    const std::string mesh = dir.write("cube.obj", kCube);
    const std::string good = npy({0, 0, 0, 1, 2, 3});
    dir.write("good.npy", good);
    dir.write("cut.npy", good.substr(0, good.size() - 5));
    dir.write("two.npy", npy({0, 0, 1, 1}, "<f4", 2));
    dir.write("complex.npy", npy({0, 0, 0, 0, 0, 0}, "<c8"));
    dir.write("header.npy", good.substr(0, 12));
    dir.write("short.csv", "1,2,3\n4,5\n");
    dir.write("word.csv", "1,2,3\n4,five,6\n");
    dir.write("nan.csv", "1,2,3\nnan,0,0\n");
    dir.write("rays.npy", npy({1, 0, 0}));
    const int before = dir.count();
    struct Case {
        std::string args, expect;
    };
    const std::vector<Case> cases = {
        {dir.file("cut.npy") + " -o out.npz", "cut.npy: 2 x 3 values of 4 bytes need 24 bytes"},
        {dir.file("two.npy") + " -o out.npz", "two.npy: array of shape (2, 2); expected N x 3"},
        {dir.file("complex.npy") + " -o out.npz", "dtype '<c8' is not supported"},
        {dir.file("header.npy") + " -o out.npz", "header of"},
        {dir.file("short.csv") + " -o out.npz", "short.csv:2: expected 3 numbers on the line"},
        {dir.file("word.csv") + " -o out.npz", "word.csv:2:"},
        {dir.file("nan.csv") + " -o out.npz", "nan.csv: row 1 is not finite"},
        {dir.file("missing.npy") + " -o out.npz", "missing.npy: cannot open"},
        {dir.file("good.npy") + " -o out.txt", "out.txt: unknown output extension"},
        {dir.file("good.npy") + " --closest -o out.npy", "a .npy file holds one array"},
        {dir.file("good.npy") + " --rays " + dir.file("rays.npy") + " -o out.npz",
         "1 directions for 2 origins"},
        {"-o out.npz", "give a points file or --sample"},
        {"--sample near -o out.npz", "needs --count"},
        {"--sample volume --count 10 --bounds 1,1,1,0,0,0 -o out.npz", "--bounds"},
        {"--sample near --count 100000000000 -o out.npz", "more than the memory budget"},
    };
    for (const Case& c : cases) {
        RunResult r = runCli("query -q " + mesh + " " + c.args, dir);
        EXPECT_EQ(r.status, 1) << c.args << "\n" << r.err;
        EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_EQ(dir.count(), before) << c.args;
    }
    RunResult flag =
        runCli("query -q " + mesh + " " + dir.file("good.npy") + " --sign ray -o x.npz", dir);
    EXPECT_EQ(flag.status, 2) << flag.err;
    EXPECT_NE(flag.err.find("--sign"), std::string::npos) << flag.err;
    EXPECT_EQ(dir.count(), before);
}

}  // namespace
}  // namespace sdft::e2e
