// The vdmap command: verbs for mapping, rendering, benchmarking and evaluation, and (with no
// argument) the workbench on the built-in scene.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <regex>

#include "app/cli/command_line.h"
#include "app/cli/error_text.h"
#include "app/verbs.h"
#include "mapping/core/temporary_paths.h"
#include "vdmap_version.h"

namespace {

// CLI11 reads 0x10 as 16 and 0b11 as 3: an option's value in another base is almost surely a typo
// (--resolution 0x10 for 0.10), so it is refused (a file or folder of that name is left alone, and
// --size and --window-size, whose WxH reads 0x10 as 0 by 10).
void refuseRadixNumbers(int argc, char** argv) {
  static const std::regex radix("[-+]?0[xXbBoO][0-9a-fA-F]+");
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i - 1]).rfind("--", 0) == 0 && !std::string(argv[i - 1]).ends_with("size") &&
        std::regex_match(argv[i], radix) && !std::filesystem::exists(argv[i]))
      throw CLI::ValidationError(argv[i - 1], std::string("'") + argv[i] +
                                                  "': a number in another base (hexadecimal, binary, octal); write "
                                                  "it in decimal");
}

// Help lines are wrapped at this many columns (a terminal's 80 to 100 show them whole).
constexpr std::size_t kHelpWidth = 100;

}  // namespace

int main(int argc, char** argv) {
  using namespace vdmap::app;
  // An interrupted export or save removes its temporary files and folders.
  vdmap::installTemporaryPathCleanup();
  CLI::App app{"vdmap: keyframe-based dense mapping with view-dependent local maps (RGB-D)\n"
               "With no verb, opens the workbench on the built-in scene."};
  app.require_subcommand(0, 1);
  // Before the verbs are added: they take their formatter from here.
  app.formatter(std::make_shared<WrappingFormatter>(kHelpWidth));
  // The project version, and the commit when the build was configured from a git checkout
  // (cmake/version.cmake); nothing is looked up at run time.
  const std::string commit = vdmap::kGitDescribe[0] ? std::string(" (git ") + vdmap::kGitDescribe + ")" : "";
  const std::string version = std::string("vdmap ") + vdmap::kVersion + commit;
  app.set_version_flag("--version", version, "print vdmap's version (and the git commit it was built from) and exit");
  addInfoCommand(app);
  addMapCommand(app);
  addRenderCommand(app);
  addSynthCommand(app);
  addBenchCommand(app);
  addEvalCommand(app);
  addGuiCommand(app);
  addParamsCommand(app);
  addQueryCommand(app);  // point queries (docs/method.md 13)
  addMeshCommand(app);
  const auto workbench = addBuiltinWorkbenchOptions(app);
  const auto print = [&app](const char* kind, const std::string& what) {
    const std::string verb = app.get_subcommands().empty() ? "" : " " + app.get_subcommands()[0]->get_name();
    std::cerr << "vdmap" << verb << ": " << kind << ": " << what << "\n";
  };
  const auto error = [&print](const std::string& what) { print("error", what); };
  // What was written to stdout must have arrived: a full disk or a closed file there (`info
  // --json > /dev/full`) is a failure, not a silent success.
  const auto written = [&error](int code) {
    std::cout.flush();
    errno = 0;
    if (std::fflush(stdout) == 0 && std::cout && !std::ferror(stdout)) return code;
    // The failed write may be an earlier one (its errno gone): then no reason is given.
    error(std::string("cannot write to standard output") +
          (errno != 0 ? std::string(": ") + std::strerror(errno) : "") + " (a full disk or a closed file?)");
    return code == 0 ? 1 : code;
  };
  // `vdmap VERB --version` too: CLI11 knows it only before a verb (the verb asked for its SEQ).
  for (int i = 2; i < argc; ++i)
    if (std::string(argv[i]) == "--version") {
      std::cout << version << "\n";
      return written(0);
    }
  try {
    refuseRadixNumbers(argc, argv);
    app.parse(argc, argv);
    if (app.get_subcommands().empty()) workbench();
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return written(app.exit(e));  // --help, --version
    // One line like every other error (CLI11's own adds "Run with --help ...").
    error(std::string(e.what()) + " (see --help)");
    return e.get_exit_code();
  } catch (const ExitWith& e) {  // the work was done; its verdict is not success (render --expect: 2)
    print("differs", e.what());
    return written(e.code);
  } catch (const std::exception& e) {  // one line naming the path and what is wrong (errorMessage)
    error(errorMessage(e));
    return 1;
  }
  return written(0);
}
