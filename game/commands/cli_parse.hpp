#pragma once
// Command-line parsing shared by every subcommand: one place decides what a usage error prints
// (the message and a one-line hint, never the whole help) and how numbers are range-checked.

#include "game/commands.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace game {

// Prints a usage error as every subcommand words it and returns 2:
//   fluiddemo COMMAND: MESSAGE
//   run 'fluiddemo COMMAND --help' for the options
inline int usageError(const std::string& command, const std::string& message) {
  std::fprintf(stderr, "fluiddemo %s: %s\nrun 'fluiddemo %s --help' for the options\n", command.c_str(),
               message.c_str(), command.c_str());
  return 2;
}

// Parses `args` into `app`. Returns -1 to go on, otherwise the exit code: 0 after printing the
// help (--help), 2 after a usage error (printed by usageError).
inline int parseCommandLine(CLI::App& app, const std::string& command, const Args& args) {
  std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 consumes from the back
  try {
    app.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    std::printf("%s", app.help().c_str());
    return 0;
  } catch (const CLI::ExtrasError& error) {
    // CLI11 joins the left-over words back to front (it expects them reversed, as parse() takes
    // them), so "--fps 30" would read "30 --fps"; app.remaining() has them in command-line order.
    const std::vector<std::string> left = app.remaining();
    if (left.empty()) return usageError(command, error.what());
    std::string message =
        left.size() > 1 ? "The following arguments were not expected:" : "The following argument was not expected:";
    for (const std::string& word : left) message += " " + word;
    return usageError(command, message);
  } catch (const CLI::ParseError& error) {
    return usageError(command, error.what());
  }
  return -1;
}

// A finite number > 0. (CLI::PositiveNumber words its range with DBL_MAX written out in full.)
inline CLI::Validator positiveNumber() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!(std::isfinite(value) && value > 0.0)) return "must be a positive number, got " + text;
        return {};
      },
      "POSITIVE");
}

// A finite number in [lo, hi]. CLI::Range lets NaN through (every comparison with it is false), so a
// "nan" given for a double reached the command; this refuses it as out of range.
inline CLI::Validator numberIn(double lo, double hi) {
  auto text_of = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return std::string(buf);
  };
  return CLI::Validator(
      [lo, hi, text_of](std::string& text) -> std::string {
        double value = 0.0;
        if (!CLI::detail::lexical_cast(text, value)) return "'" + text + "' is not a number";
        if (!(std::isfinite(value) && value >= lo && value <= hi))
          return "Value " + text + " not in range " + text_of(lo) + " to " + text_of(hi);
        return {};
      },
      "FLOAT in [" + text_of(lo) + " - " + text_of(hi) + "]");
}

}  // namespace game
