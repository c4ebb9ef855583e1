// Helper shared by the io tests: a path in the temporary directory unique to this process.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>

namespace sdft::testing {

inline std::string tempPath(const std::string& name) {
    return (std::filesystem::temp_directory_path() /
            ("sdftrace-io-" + std::to_string(::getpid()) + "-" + name))
        .string();
}

}  // namespace sdft::testing
