// Recoverable host errors: bad user input (files, JSON, flags, parameters) and I/O failures.
#pragma once

#include <stdexcept>
#include <string>

namespace sdft {

// Thrown for anything a user can fix. The message is one line that names the file, the JSON path or
// the flag, says what was wrong and what would be accepted. The CLI prints it and exits non-zero.
class InputError : public std::runtime_error {
  public:
    explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace sdft
