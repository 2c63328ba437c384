#pragma once
// An effect's parameters as one table bound to its typed params struct. Each row names a scene
// key, its range, its doc and the struct member it fills; the default is the member's own
// initialiser (read from a value-initialised struct), so a number is written once. The scene
// schema (hence the scene-file and `--set` validation), the overlay's knobs, the docs table
// (`fluiddemo scene-keys`) and the parser all come from this table.
//
//   const ParamTable<RigidBodyParams> table{
//       param<&RigidBodyParams::crates>("crates", 0, 200, "crates stacked around the fountain"), ...};
//   RigidBodyParams p = table.parse(section);  // every key of a validated section

#include "game/scene/scene_config.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <initializer_list>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace game {

template <class P>
struct ParamField {
  ParamSpec spec;                                      // key, type, range, default, doc, choices
  std::function<void(const SectionConfig&, P&)> read;  // validated section -> the bound member
};

namespace detail {
template <class T>
struct MemberOf;
template <class C, class M>
struct MemberOf<M C::*> {
  using Class = C;
  using Type = M;
};
template <auto Member>
using ClassOf = typename MemberOf<decltype(Member)>::Class;
template <auto Member>
using TypeOf = typename MemberOf<decltype(Member)>::Type;
}  // namespace detail

// A number, integer, boolean or vec3 row. `min`/`max` bound numbers, integers and each vec3
// component (ignored for booleans). The key must stay alive (string literals).
template <auto Member>
ParamField<detail::ClassOf<Member>> param(std::string_view key, double min, double max, std::string_view doc) {
  using P = detail::ClassOf<Member>;
  using M = detail::TypeOf<Member>;
  const M fallback = P{}.*Member;
  ParamField<P> field;
  field.spec.key = key;
  field.spec.min = min;
  field.spec.max = max;
  field.spec.doc = doc;
  if constexpr (std::is_same_v<M, bool>) {
    field.spec.type = ParamType::boolean;
    field.spec.default_value = {ParamType::boolean, 0.0, fallback, {}, {}};
    field.read = [key](const SectionConfig& s, P& p) { p.*Member = s.boolean(key); };
  } else if constexpr (std::is_same_v<M, glm::vec3>) {
    field.spec.type = ParamType::vec3;
    field.spec.default_value = {ParamType::vec3, 0.0, false, fallback, {}};
    field.read = [key](const SectionConfig& s, P& p) { p.*Member = s.vec3(key); };
  } else if constexpr (std::is_integral_v<M>) {
    field.spec.type = ParamType::integer;
    field.spec.default_value = {ParamType::integer, static_cast<double>(fallback), false, {}, {}};
    field.read = [key](const SectionConfig& s, P& p) { p.*Member = static_cast<M>(s.integer(key)); };
  } else {
    static_assert(std::is_floating_point_v<M>, "param<>: bind a number, integer, bool or glm::vec3 member");
    field.spec.type = ParamType::number;
    field.spec.default_value = {ParamType::number, static_cast<double>(fallback), false, {}, {}};
    field.read = [key](const SectionConfig& s, P& p) { p.*Member = static_cast<M>(s.number(key)); };
  }
  return field;
}

// A boolean row (no range).
template <auto Member>
ParamField<detail::ClassOf<Member>> param(std::string_view key, std::string_view doc) {
  static_assert(std::is_same_v<detail::TypeOf<Member>, bool>, "param<>(key, doc) is for bool members");
  return param<Member>(key, 0.0, 0.0, doc);
}

// An enum row, written as text: `names[i]` stands for `values[i]` (both arrays outlive the table;
// names are the only accepted values, the schema rejects anything else).
template <auto Member>
ParamField<detail::ClassOf<Member>> choice(std::string_view key, std::span<const std::string_view> names,
                                           std::span<const detail::TypeOf<Member>> values, std::string_view doc) {
  using P = detail::ClassOf<Member>;
  using M = detail::TypeOf<Member>;
  static_assert(std::is_enum_v<M>, "choice<>: bind an enum member");
  const M fallback = P{}.*Member;
  const auto at = std::find(values.begin(), values.end(), fallback);
  ParamField<P> field;
  field.spec.key = key;
  field.spec.type = ParamType::text;
  field.spec.doc = doc;
  field.spec.choices = names;
  field.spec.default_value = {ParamType::text, 0.0, false, {}, std::string(names[at - values.begin()])};
  field.read = [key, names, values](const SectionConfig& s, P& p) {
    const std::string& text = s.text(key);
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == text) p.*Member = values[i];
  };
  return field;
}

// A text row that takes one of `names` (which outlive the table), bound to a std::string member:
// for choices another part owns, e.g. the water backends of engine/fluid_render's registry.
template <auto Member>
ParamField<detail::ClassOf<Member>> oneOf(std::string_view key, std::span<const std::string_view> names,
                                          std::string_view doc) {
  using P = detail::ClassOf<Member>;
  static_assert(std::is_same_v<detail::TypeOf<Member>, std::string>, "oneOf<>: bind a std::string member");
  ParamField<P> field;
  field.spec.key = key;
  field.spec.type = ParamType::text;
  field.spec.doc = doc;
  field.spec.choices = names;
  field.spec.default_value = {ParamType::text, 0.0, false, {}, P{}.*Member};
  field.read = [key](const SectionConfig& s, P& p) { p.*Member = s.text(key); };
  return field;
}

// A free-text row (any value; e.g. a file name) bound to a std::string member.
template <auto Member>
ParamField<detail::ClassOf<Member>> text(std::string_view key, std::string_view doc) {
  using P = detail::ClassOf<Member>;
  static_assert(std::is_same_v<detail::TypeOf<Member>, std::string>, "text<>: bind a std::string member");
  ParamField<P> field;
  field.spec.key = key;
  field.spec.type = ParamType::text;
  field.spec.doc = doc;
  field.spec.default_value = {ParamType::text, 0.0, false, {}, P{}.*Member};
  field.read = [key](const SectionConfig& s, P& p) { p.*Member = s.text(key); };
  return field;
}

// Marks a row fixed: read when the effect is built, and on a restart; the overlay's edit of it
// waits for the restart (ParamSpec::live).
template <class P>
ParamField<P> fixed(ParamField<P> field) {
  field.spec.live = false;
  return field;
}

template <class P>
struct ParamTable {
  std::vector<ParamField<P>> fields;
  std::vector<ParamSpec> specs;  // the rows as the scene schema sees them, in table order

  ParamTable(std::initializer_list<ParamField<P>> rows) : fields(rows) {
    for (const ParamField<P>& f : fields) specs.push_back(f.spec);
  }
  // Every row of a validated section (it holds every key) read into a value-initialised P.
  P parse(const SectionConfig& section) const {
    P p{};
    for (const ParamField<P>& f : fields) f.read(section, p);
    return p;
  }
  // The live rows of a validated section read over `built` (the values the effect was built
  // with): what Effect::applyLive takes, the fixed rows staying as built.
  P parseLive(const SectionConfig& section, const P& built) const {
    P p = built;
    for (const ParamField<P>& f : fields)
      if (f.spec.live) f.read(section, p);
    return p;
  }
};

}  // namespace game
