#pragma once
// Subcommands of the fluiddemo executable. Each takes the arguments after its own name,
// prints its own usage/errors, and returns the process exit code, by one rule:
//   0 ok;
//   2 usage: an unknown option, a bad or conflicting value (--set included), a missing required
//     argument, an output that exists without --force, a picture output not named .png;
//   1 failure: an input that is missing or bad, an output folder that cannot be written in, and
//     anything that fails while running.
// Outputs are checked before any work (game/commands/cli_outputs.hpp); content is found through
// game/paths.hpp whatever the working folder. tests/game/cli_exit_codes.sh checks the rule.

#include <string>
#include <vector>

namespace game {

using Args = std::vector<std::string>;

int playCommand(const Args& args);           // game/commands/play_command.cpp
int smokeCommand(const Args& args);          // game/commands/play_command.cpp
int soakCommand(const Args& args);           // game/commands/soak_command.cpp
int replayCommand(const Args& args);         // game/commands/replay_command.cpp (game/replay)
int meshCommand(const Args& args);           // game/commands/mesh_command.cpp (fluid/surface)
int renderCommand(const Args& args);         // game/commands/render_command.cpp (engine/fluid_render)
int simulateCommand(const Args& args);       // game/commands/simulate_command.cpp (fluid/sph)
int bakeColliderCommand(const Args& args);   // game/commands/collider_commands.cpp (fluid/collide)
int queryColliderCommand(const Args& args);  // game/commands/collider_commands.cpp (fluid/collide)
int sceneKeysCommand(const Args& args);      // game/commands/scene_keys_command.cpp (the schema)

}  // namespace game
