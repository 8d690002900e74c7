#pragma once
// How every front-end reads its command line: --help and --version print and end the program with
// status 0; a bad option or value is one line, "PROGRAM: error: ...", and status 2, as for every other
// refused input (ProgramMain.h). CLI11's own exit codes (105, 109, ...) said nothing to a script.

#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>

#include "voxfuse/Version.h"

namespace voxfuse::app {

// --version prints "PROGRAM VERSION".
inline void addVersionFlag(CLI::App& cli, const char* program) {
    cli.set_version_flag("--version", std::string(program) + " " + VOXFUSE_VERSION_STRING,
                         "print the version and exit");
}

// Parses the command line. Returns the status to exit with when the program ends here (help, version,
// an error), nothing when it goes on.
inline std::optional<int> parseCommandLine(CLI::App& cli, int argc, char** argv, const char* program) {
    try {
        cli.parse(argc, argv);
        return std::nullopt;
    } catch (const CLI::CallForHelp& e) {
        return cli.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return cli.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return cli.exit(e);
    } catch (const CLI::Success&) {  // an option that printed what was asked (--tracker-keys)
        return 0;
    } catch (const CLI::ParseError& e) {
        std::cerr << program << ": error: " << e.what() << " (see " << program << " --help)\n";
        return 2;
    }
}

}  // namespace voxfuse::app
