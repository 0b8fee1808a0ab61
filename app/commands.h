#pragma once
// Each verb of the vdmap command registers itself on the top-level CLI11 app. A verb's callback
// throws std::exception on failure; main() turns that into a one-line error and exit code 1.

#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

namespace vdmap::app {

/// Thrown by verbs that exist in the contract but are not implemented yet (exit code 2).
struct NotBuiltYet : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void addInfoCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addSynthCommand(CLI::App& app);
void addMapCommand(CLI::App& app);
void addBenchCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);

/// Registers a verb that says clearly it is not built yet and which issue will bring it.
void addPlannedCommand(CLI::App& app, const std::string& name, const std::string& what,
                       const std::string& issue);

}  // namespace vdmap::app

#include "mapping/io/tum_sequence.h"

namespace vdmap::app {

/// The options every verb that reads a sequence shares: SEQ, --camera, --frames.
struct SequenceArgs {
  std::string folder;
  std::string camera;
  std::string frames;
};
void addSequenceArgs(CLI::App& verb, SequenceArgs& args);
/// Opens the sequence the arguments name (throws InputError / std::invalid_argument).
TumSequence openSequence(const SequenceArgs& args);

}  // namespace vdmap::app
