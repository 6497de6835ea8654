// Error types: every library error is an exception carrying enough context to act on.
#pragma once
#include <stdexcept>
#include <string>

namespace penumbra {

// Where a scene object or value was declared (file and line of the XML element).
struct SourceLocation {
    std::string file;
    int line = 0;
    std::string str() const { return file.empty() ? std::string("<unknown>") : file + ":" + std::to_string(line); }
};

class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Error in a scene description. what() is "file:line: message".
class LoadError : public Error {
public:
    LoadError(const SourceLocation& loc, const std::string& msg) : Error(loc.str() + ": " + msg), location(loc) {}
    SourceLocation location;
};

} // namespace penumbra
