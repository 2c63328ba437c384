// `fluiddemo scene-keys`: every scene section and key as a Markdown table, written from the
// schema, i.e. from the effects' parameter tables (game/effects/) and the scene/camera rows. The
// docs' key tables are this command's output.
#include "game/commands.hpp"
#include "game/commands/cli_parse.hpp"
#include "game/effects/effect.hpp"
#include "game/scene/scene_config.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

namespace game {
namespace {

std::string typeName(const ParamSpec& spec) {
  switch (spec.type) {
    case ParamType::number:
      return "number";
    case ParamType::integer:
      return "integer";
    case ParamType::boolean:
      return "bool";
    case ParamType::vec3:
      return "vec3";
    case ParamType::text:
      break;
  }
  std::string choices;
  for (std::string_view choice : spec.choices) choices += (choices.empty() ? "" : ", ") + std::string(choice);
  return choices.empty() ? "text" : "one of " + choices;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string whole(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.0f", value);
  return text;
}

// A Markdown table cell: '|' would end the cell.
std::string cell(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string defaultText(const ParamSpec& spec) {
  const ParamValue& v = spec.default_value;
  switch (spec.type) {
    case ParamType::number:
      return number(v.number);
    case ParamType::integer:
      return whole(v.number);
    case ParamType::boolean:
      return v.boolean ? "true" : "false";
    case ParamType::vec3: {
      std::string text = "[";  // appended piecewise: GCC 12 warns (-Wrestrict) on "[" + string
      text += number(v.vec.x);
      text += ", ";
      text += number(v.vec.y);
      text += ", ";
      text += number(v.vec.z);
      text += "]";
      return text;
    }
    case ParamType::text:
      return v.text;
  }
  return {};
}

std::string rangeText(const ParamSpec& spec) {
  if (spec.type == ParamType::boolean || spec.type == ParamType::text) return "";
  if (spec.type == ParamType::integer) return whole(spec.min) + " .. " + whole(spec.max);
  return number(spec.min) + " .. " + number(spec.max);
}

}  // namespace

int sceneKeysCommand(const Args& args) {
  // No options, but the same parser as every subcommand: --help works and a stray word is the same
  // usage error everywhere.
  CLI::App app{
      "Every scene section and key with its type, range, default and meaning, as Markdown (the docs' "
      "key tables are this output).",
      "fluiddemo scene-keys"};
  bool columns = false;
  app.add_flag("--columns", columns,
               "print the replay CSV's effect columns instead (the table in docs/replay.md), from the effects' files");
  if (const int code = parseCommandLine(app, "scene-keys", args); code >= 0) return code;
  if (columns) {
    std::printf("<!-- written by `fluiddemo scene-keys --columns` from the effects' column lists; do not edit -->\n");
    std::printf("| column | effect | meaning |\n|---|---|---|\n");
    for (const ColumnSpec& column : frameColumnCatalogue()) {
      std::string owners;
      for (const EffectDesc* desc : effectRegistry())
        for (const ColumnSpec& own : desc->columns)
          if (own.name == column.name) {
            if (!owners.empty()) owners += ", ";
            owners += desc->name;
          }
      const std::string name(column.name), doc(column.doc);
      std::printf("| `%s` | %s | %s |\n", name.c_str(), owners.c_str(), cell(doc).c_str());
    }
    return 0;
  }
  std::printf("<!-- written by `fluiddemo scene-keys` from the effects' parameter tables; do not edit -->\n");
  for (const SectionSpec& section : sceneSchema()) {
    const std::string name(section.name), doc(section.doc);
    std::printf("\n**`%s`**%s: %s\n\n", name.c_str(), section.is_effect ? " (effect)" : "", doc.c_str());
    std::printf("| key | type | range | default | live | meaning |\n|---|---|---|---|---|---|\n");
    for (const ParamSpec& spec : section.params) {
      const std::string key(spec.key), meaning(spec.doc);
      // Live: the overlay's edit applies at once; "restart": the effect is built with it.
      const char* live = !section.is_effect ? "" : spec.live ? "yes" : "restart";
      std::printf("| `%s` | %s | %s | %s | %s | %s |\n", key.c_str(), typeName(spec).c_str(), rangeText(spec).c_str(),
                  defaultText(spec).c_str(), live, cell(meaning).c_str());
    }
  }
  return 0;
}

}  // namespace game
