// Helpers shared by the XML parser and XML error tests.
#pragma once
#include "core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

namespace penumbra::test {

// Wraps the body in a version 3 scene whose first body line is line 2.
inline std::string scene(const std::string& body) {
    return "<scene version=\"3.0.0\">\n" + body + "\n</scene>\n";
}

// The message of the LoadError thrown by `fn`, checked to be one line starting with its location (fails the
// test if nothing or something else is thrown).
template <typename Fn> std::string load_error_of(Fn&& fn) {
    try {
        fn();
    } catch (const LoadError& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "multi-line error: " << msg;
        EXPECT_EQ(msg.rfind(e.location.str() + ": ", 0), 0u)
            << "message does not start with its location: " << msg;
        return msg;
    }
    ADD_FAILURE() << "no LoadError thrown";
    return {};
}

// A scratch directory named after the running test, emptied on creation and removed on destruction.
class TempDir {
  public:
    TempDir() {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = "penumbra_" + std::string(info->test_suite_name()) + "_" + info->name();
        std::replace(name.begin(), name.end(), '/', '_'); // parameterized tests
        path_ = std::filesystem::temp_directory_path() / name;
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() { std::filesystem::remove_all(path_); }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    // Writes `text` to the relative path `rel` (creating its folders); returns the full path.
    std::string write(const std::string& rel, const std::string& text) const {
        const std::filesystem::path p = path_ / rel;
        std::filesystem::create_directories(p.parent_path());
        std::ofstream(p) << text;
        return p.string();
    }
    std::string str() const { return path_.string(); }

  private:
    std::filesystem::path path_;
};

} // namespace penumbra::test
