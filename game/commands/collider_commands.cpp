#include "game/commands.hpp"

#include <cstdio>

namespace game {

// Placeholder until its module lands; replaced by the real command.
int bakeColliderCommand(const Args&) {
  std::fprintf(stderr, "fluiddemo: this subcommand is not built yet\n");
  return 2;
}

// Placeholder until its module lands; replaced by the real command.
int queryColliderCommand(const Args&) {
  std::fprintf(stderr, "fluiddemo: this subcommand is not built yet\n");
  return 2;
}

}  // namespace game
