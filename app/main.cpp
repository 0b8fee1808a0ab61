// The vdmap command: verbs for mapping, rendering, benchmarking and evaluation, and (with no
// argument) the workbench on the built-in scene.
#include <iostream>

#include "app/commands.h"

namespace vdmap::app {

void addPlannedCommand(CLI::App& app, const std::string& name, const std::string& what,
                       const std::string& issue) {
  auto* verb = app.add_subcommand(name, what + " (not built yet)");
  verb->allow_extras();
  verb->callback([name, issue] {
    throw NotBuiltYet("'vdmap " + name + "' is not built yet (planned in issue " + issue + ")");
  });
}

}  // namespace vdmap::app

int main(int argc, char** argv) {
  using namespace vdmap::app;
  CLI::App app{"vdmap: keyframe-based dense mapping with view-dependent local maps (RGB-D)\n"
               "With no verb, opens the workbench on the built-in scene."};
  app.require_subcommand(0, 1);
  addInfoCommand(app);
  addMapCommand(app);
  addRenderCommand(app);
  addSynthCommand(app);
  addBenchCommand(app);
  addEvalCommand(app);
  addPlannedCommand(app, "gui", "Open the workbench on a sequence", "#7");
  try {
    app.parse(argc, argv);
    if (app.get_subcommands().empty())
      throw NotBuiltYet("the workbench is not built yet (planned in issue #7); see 'vdmap --help'");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const NotBuiltYet& e) {
    std::cerr << "vdmap: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    const std::string verb = app.get_subcommands().empty() ? "" : " " + app.get_subcommands()[0]->get_name();
    std::cerr << "vdmap" << verb << ": error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
