// fluiddemo: command-line entry. Dispatches to one subcommand (see game/commands.hpp).
#include "game/commands.hpp"

#include <cstdio>
#include <string>
#include <string_view>

namespace {

struct Subcommand {
  std::string_view name;
  std::string_view summary;
  int (*run)(const game::Args&);
};

constexpr Subcommand kSubcommands[] = {
    {"play", "play a scene in a window (headless when no display): play [SCENE] [options]", game::playCommand},
    {"smoke", "run scenes headless and check each frame: smoke [--scene S | --all] [--frames N] [--out DIR]",
     game::smokeCommand},
    {"soak", "long headless runs with crate and explosive throws, checked every frame: soak [--scene S | --all] [--seconds T]",
     game::soakCommand},
    {"replay", "play a replay file, check its hashes, time each frame: replay FILE [--csv OUT] [--png OUT]",
     game::replayCommand},
    {"mesh", "particles -> triangle mesh by marching slices: mesh --in FILE --out FILE", game::meshCommand},
    {"render", "draw a particle set headless with one water renderer: render --in FILE --method M --out IMAGE.png",
     game::renderCommand},
    {"simulate", "run an SPH scene without a window: simulate --scene NAME --seconds T", game::simulateCommand},
    {"bake-collider", "bake depth-map colliders from a model: bake-collider MODEL --out FILE",
     game::bakeColliderCommand},
    {"query-collider", "signed distance and normal per point: query-collider FILE --points FILE.xyz",
     game::queryColliderCommand},
    {"scene-keys", "every scene key with its type, range, default and meaning, as Markdown: scene-keys",
     game::sceneKeysCommand},
};

void printUsage(std::FILE* stream) {
  std::fprintf(stream, "usage: fluiddemo [SUBCOMMAND] [options]   (no subcommand = play fountain)\n\n");
  for (const Subcommand& command : kSubcommands) {
    std::fprintf(stream, "  %-15.*s %.*s\n", static_cast<int>(command.name.size()), command.name.data(),
                 static_cast<int>(command.summary.size()), command.summary.data());
  }
  std::fprintf(stream, "\nRun `fluiddemo SUBCOMMAND --help` for the options of one subcommand.\n");
}

}  // namespace

int main(int argc, char** argv) {
  game::Args args(argv + 1, argv + argc);
  if (!args.empty() && (args[0] == "--help" || args[0] == "-h" || args[0] == "help")) {
    printUsage(stdout);
    return 0;
  }
  // No subcommand, or options first: `fluiddemo --headless` plays the default scene.
  if (args.empty() || args[0].starts_with("-")) return game::playCommand(args);
  for (const Subcommand& command : kSubcommands) {
    if (args[0] == command.name) return command.run(game::Args(args.begin() + 1, args.end()));
  }
  std::fprintf(stderr, "fluiddemo: unknown subcommand '%s'\n\n", args[0].c_str());
  printUsage(stderr);
  return 2;
}
