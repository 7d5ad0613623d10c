// The quadify subcommands. Each registers its options on the CLI11 app and runs when selected.
#pragma once

#include "report.h"

#include <CLI/CLI.hpp>

#include <functional>

namespace quadify::cli {

// A registered subcommand: run() is called when the user selected it; returns an exit code.
using CommandRunner = std::function<int(const CommonOptions&)>;

CommandRunner register_info(CLI::App& app);
CommandRunner register_check(CLI::App& app);
CommandRunner register_param(CLI::App& app);
CommandRunner register_remesh(CLI::App& app);
CommandRunner register_compare(CLI::App& app);

}  // namespace quadify::cli
