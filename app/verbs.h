#pragma once
// Each verb of the vdmap command registers itself on the top-level CLI11 app. A verb's callback
// throws std::exception on failure; main() turns that into a one-line error and exit code 1.
#include <functional>

#include <CLI/CLI.hpp>

namespace vdmap::app {

void addInfoCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addSynthCommand(CLI::App& app);
void addMapCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);
void addGuiCommand(CLI::App& app);
/// `vdmap query MAP --op ...`: point queries and the planners' exports (docs/method.md 13).
void addQueryCommand(CLI::App& app);
/// `vdmap params [--markdown]`: the parameter table for users, or docs/parameters.md.
void addParamsCommand(CLI::App& app);
/// `vdmap mesh MAP --out FILE`: the surface mesh (docs/method.md 14).
void addMeshCommand(CLI::App& app);
/// The workbench options of `vdmap` without a verb; the returned function opens the workbench
/// on the built-in scene (throws std::runtime_error when it ends on an error).
std::function<void()> addBuiltinWorkbenchOptions(CLI::App& app);

}  // namespace vdmap::app
