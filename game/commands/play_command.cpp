#include "game/commands.hpp"

#include <cstdio>

namespace game {

// Placeholder until its module lands; replaced by the real command.
int playCommand(const Args&) {
  std::fprintf(stderr, "fluiddemo: this subcommand is not built yet\n");
  return 2;
}

// Placeholder until its module lands; replaced by the real command.
int smokeCommand(const Args&) {
  std::fprintf(stderr, "fluiddemo: this subcommand is not built yet\n");
  return 2;
}

}  // namespace game
