// The `penumbra` command line: a thin front over the library.
#include "cli.h"

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
    CLI::App app{"penumbra: a physics-based differentiable renderer"};
    app.require_subcommand(1);
    penumbra::cli::add_render_commands(app);
    penumbra::cli::add_diff_commands(app);
    penumbra::cli::add_optimize_command(app);
    penumbra::cli::add_study_commands(app);
    penumbra::cli::add_suite_command(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "penumbra: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
