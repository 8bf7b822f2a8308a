// The one error a user sees for bad input: which file, and why.
#pragma once

#include <stdexcept>
#include <string>

namespace uvpress {

class InputError : public std::runtime_error {
 public:
  InputError(std::string file, const std::string& reason) : std::runtime_error(reason), file_(std::move(file)) {}
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

}  // namespace uvpress
