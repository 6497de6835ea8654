// Output safety (issue 18): outputs are written atomically (core/atomic_file.h), and a run stopped by SIGINT
// or SIGTERM exits 130 / 143 with a message, leaving no partial and no temporary file.
#include "core/atomic_file.h"
#include "core/error.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

using namespace penumbra;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string source_dir = PENUMBRA_SOURCE_DIR;

fs::path test_root() {
    return fs::temp_directory_path() / ("penumbra_interrupt_" + std::to_string(::getpid()));
}

struct AtomicFile : ::testing::Test {
    void TearDown() override { fs::remove_all(test_root()); }
};
struct CliInterrupt : AtomicFile {};

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = test_root() / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> files_in(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& entry : fs::recursive_directory_iterator(dir))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// `penumbra args...` in the background, stdout discarded, stderr to a file (outside the output directories).
class CliProcess {
  public:
    CliProcess(const std::vector<std::string>& args, const fs::path& stderr_path)
        : stderr_path_(stderr_path) {
        std::vector<std::string> argv_strings{PENUMBRA_CLI};
        argv_strings.insert(argv_strings.end(), args.begin(), args.end());
        std::vector<char*> argv;
        for (std::string& a : argv_strings)
            argv.push_back(a.data());
        argv.push_back(nullptr);
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
        posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path.c_str(),
                                         O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (posix_spawn(&pid_, PENUMBRA_CLI, &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
        posix_spawn_file_actions_destroy(&actions);
    }
    ~CliProcess() {
        if (pid_ > 0 && !exited_) {
            ::kill(pid_, SIGKILL);
            ::waitpid(pid_, nullptr, 0);
        }
    }
    bool started() const { return pid_ > 0; }

    // Whether the process has installed its SIGINT handler (/proc/<pid>/status: SigCgt, a hexadecimal mask),
    // so that a signal sent now is handled rather than fatal.
    bool catches_sigint() const {
        std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
        for (std::string line; std::getline(status, line);)
            if (line.rfind("SigCgt:", 0) == 0)
                return (std::stoull(line.substr(7), nullptr, 16) >> (SIGINT - 1)) & 1;
        return false;
    }
    // Waits (at most `timeout`) until `ready()` holds while the process runs.
    template <typename Ready> bool wait_until(const Ready& ready, std::chrono::milliseconds timeout) {
        const auto end = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < end) {
            if (ready()) return true;
            std::this_thread::sleep_for(10ms);
        }
        return false;
    }
    void signal(int sig) { ::kill(pid_, sig); }

    // The wait status once the process is gone; false if it still runs after `timeout`.
    bool wait_exit(std::chrono::milliseconds timeout) {
        const auto end = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < end) {
            if (::waitpid(pid_, &status_, WNOHANG) == pid_) return exited_ = true;
            std::this_thread::sleep_for(10ms);
        }
        return false;
    }
    int exit_code() const { return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1; }
    int killed_by() const { return WIFSIGNALED(status_) ? WTERMSIG(status_) : 0; }
    std::string error_output() const { return read_file(stderr_path_); }

  private:
    pid_t pid_ = -1;
    int status_ = 0;
    bool exited_ = false;
    fs::path stderr_path_;
};

// Starts `args`, waits until its handler is installed and then `running` more, sends `sig` and expects the
// exit code 128 + sig within a few seconds.
void interrupt(CliProcess& p, int sig, std::chrono::milliseconds running) {
    ASSERT_TRUE(p.started());
    ASSERT_TRUE(p.wait_until([&] { return p.catches_sigint(); }, 5000ms)) << p.error_output();
    std::this_thread::sleep_for(running);
    p.signal(sig);
    ASSERT_TRUE(p.wait_exit(5000ms)) << "still running 5 s after the signal";
    EXPECT_EQ(p.exit_code(), 128 + sig) << p.error_output();
}

} // namespace

TEST_F(AtomicFile, AWriterThatThrowsLeavesNeitherTargetNorTemporaryFile) {
    const fs::path dir = fresh_dir("unit");
    const std::string path = (dir / "out.txt").string();
    try {
        write_file_atomically(path, [](const std::string& tmp) {
            std::ofstream(tmp) << "half a fi";
            throw Error("disk on fire");
        });
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("'" + path + "'"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("disk on fire"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(files_in(dir).empty());

    // An existing target keeps its old content when the new write fails, and takes the new one when it
    // succeeds.
    write_text_atomically(path, "old\n");
    EXPECT_THROW(write_file_atomically(path,
                                       [](const std::string& tmp) {
                                           std::ofstream(tmp) << "new, partial";
                                           throw std::runtime_error("interrupted mid-write");
                                       }),
                 Error);
    EXPECT_EQ(read_file(path), "old\n");
    EXPECT_EQ(files_in(dir), std::vector<std::string>{"out.txt"});
    write_text_atomically(path, "new\n");
    EXPECT_EQ(read_file(path), "new\n");
    EXPECT_EQ(files_in(dir), std::vector<std::string>{"out.txt"});
}

TEST_F(AtomicFile, TemporaryNamesAreUniqueBesideTheTargetAndFailuresNameIt) {
    const fs::path dir = fresh_dir("names");
    const std::string path = (dir / "a.png").string();
    const std::string t1 = atomic_temp_path(path), t2 = atomic_temp_path(path);
    EXPECT_NE(t1, t2);
    EXPECT_EQ(fs::path(t1).parent_path(), dir);
    EXPECT_NE(t1.find(std::to_string(::getpid())), std::string::npos) << t1;
    // A directory in the way: the rename fails, the error names the target, no temporary file remains.
    fs::create_directories(dir / "blocked" / "inside");
    try {
        write_text_atomically((dir / "blocked").string(), "x");
        FAIL() << "expected an Error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find((dir / "blocked").string()), std::string::npos) << e.what();
    }
    // A missing directory: cannot even create the temporary file.
    EXPECT_THROW(write_text_atomically((dir / "missing" / "x.txt").string(), "x"), Error);
    EXPECT_EQ(files_in(dir), (std::vector<std::string>{"blocked", "inside"}));
}

// (a) Ctrl-C during a long render: exit 130, the message, and nothing in the output directory.
TEST_F(CliInterrupt, SigintStopsARenderWithExit130AndNoOutput) {
    const fs::path dir = fresh_dir("render"), out = dir / "out";
    fs::create_directories(out);
    CliProcess p({"render", source_dir + "/scenes/cbox/cbox.xml", "-D", "res=64", "--spp", "1000000", "-q",
                  "-o", (out / "cbox.exr").string()},
                 dir / "stderr.txt");
    ASSERT_NO_FATAL_FAILURE(interrupt(p, SIGINT, 300ms));
    EXPECT_NE(p.error_output().find("penumbra: interrupted (SIGINT); no output written"), std::string::npos)
        << p.error_output();
    EXPECT_TRUE(files_in(out).empty());
}

// (b) SIGTERM during a derivative (psdr: calibration, interior and boundary passes): exit 143. (c) An output
// file that existed before the run is left as it was.
TEST_F(CliInterrupt, SigtermStopsADerivativeWithExit143AndKeepsAnOldOutput) {
    const fs::path dir = fresh_dir("derivative"), out = dir / "out";
    fs::create_directories(out);
    std::ofstream(out / "d.exr") << "an earlier run's output";
    CliProcess p({"derivative", source_dir + "/scenes/validation/shadow.xml", "--param",
                  "occluder.translate=1,0,0", "--spp", "1000000", "-q", "-o", (out / "d.exr").string(),
                  "--stderr", (out / "se.exr").string()},
                 dir / "stderr.txt");
    ASSERT_NO_FATAL_FAILURE(interrupt(p, SIGTERM, 300ms));
    EXPECT_NE(p.error_output().find("penumbra: interrupted (SIGTERM); no output written"), std::string::npos)
        << p.error_output();
    EXPECT_EQ(read_file(out / "d.exr"), "an earlier run's output");
    EXPECT_EQ(files_in(out), std::vector<std::string>{"d.exr"});
}

// SIGTERM during an optimization: log.csv holds whole lines (it is rewritten atomically each iteration) and
// the message says how far it goes.
TEST_F(CliInterrupt, SigtermStopsAnOptimizationWithACompleteLog) {
    const fs::path dir = fresh_dir("optimize"), out = dir / "out";
    std::ofstream(dir / "config.json") << R"({
      "scene": ")" << source_dir << R"(/scenes/optimize/scene.xml",
      "defines": {"res": 16},
      "parameters": {"metal.alpha": {"init": 0.5, "lr": 0.02, "bounds": [0.01, 1]}},
      "target": {"values": {}, "spp": 4},
      "loss": "l2", "iterations": 1000000, "spp": 2, "gradient_spp": 2, "snapshot_every": 0,
      "output": ")" << out.string() << R"("})";
    CliProcess p({"optimize", (dir / "config.json").string(), "-q"}, dir / "stderr.txt");
    ASSERT_TRUE(p.started());
    // Until at least two iterations are logged (header + 2 lines).
    auto lines = [&] {
        const std::string log = read_file(out / "log.csv");
        return std::count(log.begin(), log.end(), '\n');
    };
    ASSERT_TRUE(p.wait_until([&] { return lines() >= 3; }, 10000ms)) << p.error_output();
    ASSERT_NO_FATAL_FAILURE(interrupt(p, SIGTERM, 0ms));
    const std::string log = read_file(out / "log.csv"), message = p.error_output();
    ASSERT_FALSE(log.empty());
    EXPECT_EQ(log.back(), '\n');
    std::istringstream rows(log);
    std::string header, row;
    std::getline(rows, header);
    const auto fields = [](const std::string& s) { return std::count(s.begin(), s.end(), ','); };
    int logged = 0;
    while (std::getline(rows, row)) {
        EXPECT_EQ(fields(row), fields(header)) << row;
        ++logged;
    }
    EXPECT_NE(message.find("penumbra: interrupted (SIGTERM); complete in " + out.string() +
                           ": the targets (.exr, .png) of 1 view(s), log.csv (iterations 0-" +
                           std::to_string(logged - 1) + " of 1000000)"),
              std::string::npos)
        << message;
    for (const std::string& name : files_in(out))
        EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    EXPECT_FALSE(fs::exists(out / "result.json"));
}

// A run that cannot reach a check (here blocked opening a mesh that is a FIFO nobody writes) still dies on
// the second signal, by the default action.
TEST_F(CliInterrupt, ASecondSignalKillsARunThatDoesNotStop) {
    const fs::path dir = fresh_dir("stuck");
    ASSERT_EQ(::mkfifo((dir / "mesh.obj").c_str(), 0600), 0);
    std::ofstream(dir / "scene.xml") << R"(<scene version="3.0.0">
      <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
      <shape type="obj"><string name="filename" value="mesh.obj"/></shape>
    </scene>)";
    CliProcess p({"render", (dir / "scene.xml").string(), "-q", "-o", (dir / "out.exr").string()},
                 dir / "stderr.txt");
    ASSERT_TRUE(p.wait_until([&] { return p.catches_sigint(); }, 5000ms));
    std::this_thread::sleep_for(100ms);
    p.signal(SIGINT);
    EXPECT_FALSE(p.wait_exit(300ms)) << "the first signal only asks the work to stop";
    p.signal(SIGINT);
    ASSERT_TRUE(p.wait_exit(5000ms));
    EXPECT_EQ(p.killed_by(), SIGINT);
    EXPECT_FALSE(fs::exists(dir / "out.exr"));
}
