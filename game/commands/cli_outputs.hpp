#pragma once
// The files a subcommand will write, checked before it starts any work: a replay or a bake that
// runs for minutes must not end in "cannot open for writing". Every subcommand applies the one
// exit-code rule of game/commands.hpp to its outputs:
//   2 (usage): the file exists and --force was not given, the name is a folder, or a PNG output
//              is not named .png (the writers write PNG bytes whatever the name says);
//   1 (failure): the folder cannot be created or written in (the message gives strerror's reason).
// A missing folder is created at the check (as the PNG writer always did), so that the check is
// made on the folder the file will be written in.

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>

namespace game {

// Prints "fluiddemo COMMAND: FLAG PATH: REASON" (FLAG empty for a positional) and returns `code`.
inline int outputProblem(int code, std::string_view command, std::string_view flag, const std::filesystem::path& path,
                         const std::string& reason) {
  std::fprintf(stderr, "fluiddemo %.*s: %.*s%s%s: %s\n", static_cast<int>(command.size()), command.data(),
               static_cast<int>(flag.size()), flag.data(), flag.empty() ? "" : " ", path.c_str(), reason.c_str());
  return code;
}

// -1 when `path` can be created, or with `force` replaced; otherwise prints
//   fluiddemo COMMAND: FLAG PATH: REASON
// and returns the exit code. `flag` names the option ("--csv"), empty for a positional.
inline int checkOutputFile(std::string_view command, std::string_view flag, const std::filesystem::path& path,
                           bool force) {
  auto fail = [&](int code, const std::string& reason) { return outputProblem(code, command, flag, path, reason); };
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status)) return fail(2, "is a folder (name a file)");
  if (std::filesystem::exists(status)) {
    if (!force) return fail(2, "exists (pass --force to replace it)");
    if (::access(path.c_str(), W_OK) != 0) return fail(1, std::string("cannot replace it: ") + std::strerror(errno));
    return -1;
  }
  const std::filesystem::path folder = path.parent_path().empty() ? "." : path.parent_path();
  if (std::filesystem::create_directories(folder, ec); ec)
    return fail(1, "cannot create the folder " + folder.string() + ": " + ec.message());
  // access() answers for permissions and a read-only file system alike, without creating the file.
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    return fail(1, "cannot create it in " + folder.string() + ": " + std::strerror(errno));
  return -1;
}

// checkOutputFile for an image output, whose name must end in .png (any case).
inline int checkPngOutput(std::string_view command, std::string_view flag, const std::filesystem::path& path,
                          bool force) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".png") return outputProblem(2, command, flag, path, "only PNG is written: name the file .png");
  return checkOutputFile(command, flag, path, force);
}

// A folder that will receive outputs: created now with its parents if missing, and writable.
// -1 to go on, else 1 after printing the reason.
inline int prepareOutputFolder(std::string_view command, std::string_view flag, const std::filesystem::path& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  std::string reason = ec ? ec.message() : "";
  if (!ec && ::access(folder.c_str(), W_OK | X_OK) != 0) reason = std::strerror(errno);
  if (reason.empty()) return -1;
  return outputProblem(1, command, flag, folder, "cannot write in it: " + reason);
}

}  // namespace game
