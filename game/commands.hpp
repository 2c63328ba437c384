#pragma once
// Subcommands of the fluiddemo executable. Each takes the arguments after its own name,
// prints its own usage/errors, and returns the process exit code (0 ok, 1 failure, 2 usage).

#include <string>
#include <vector>

namespace game {

using Args = std::vector<std::string>;

int playCommand(const Args& args);           // game/commands/play_command.cpp
int smokeCommand(const Args& args);          // game/commands/play_command.cpp
int soakCommand(const Args& args);           // game/commands/soak_command.cpp
int replayCommand(const Args& args);         // game/commands/replay_command.cpp (game/replay)
int meshCommand(const Args& args);           // game/commands/mesh_command.cpp (fluid/surface)
int simulateCommand(const Args& args);       // game/commands/simulate_command.cpp (fluid/sph)
int bakeColliderCommand(const Args& args);   // game/commands/collider_commands.cpp (fluid/collide)
int queryColliderCommand(const Args& args);  // game/commands/collider_commands.cpp (fluid/collide)
int sceneKeysCommand(const Args& args);      // game/commands/scene_keys_command.cpp (the schema)

}  // namespace game
