#include "scene/scene_set.hpp"

#include <cctype>
#include <vector>

#include "scene/scene_error.hpp"

namespace dem {

namespace {

// One step of a key path: a table key, or an index into an array.
struct Step {
  std::string key;
  long index = -1;  // >= 0: an array index
};

bool all_digits(const std::string& s) {
  if (s.empty() || s.size() > 9) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  return true;
}

std::vector<Step> steps_of(const std::string& key) {
  auto fail = [&](const std::string& why) { throw SceneError(why); };
  if (key.empty()) fail("an empty key");
  std::vector<Step> out;
  std::size_t pos = 0;
  while (pos <= key.size()) {
    const std::size_t dot = key.find('.', pos);
    std::string part = key.substr(pos, dot == std::string::npos ? std::string::npos : dot - pos);
    pos = dot == std::string::npos ? key.size() + 1 : dot + 1;
    if (part.empty()) fail("not a key path (name.sub, name.0.sub or name[0].sub)");
    std::vector<long> indices;
    while (!part.empty() && part.back() == ']') {  // name[i] (or name[i][j])
      const std::size_t open = part.rfind('[');
      const std::string digits = open == std::string::npos ? "" : part.substr(open + 1, part.size() - open - 2);
      if (!all_digits(digits)) fail("not a key path (name.sub, name.0.sub or name[0].sub)");
      indices.insert(indices.begin(), std::stol(digits));
      part.erase(open);
    }
    if (all_digits(part) && indices.empty() && !out.empty()) {
      out.push_back({"", std::stol(part)});
      continue;
    }
    if (part.empty()) fail("not a key path (name.sub, name.0.sub or name[0].sub)");
    out.push_back({part, -1});
    for (long i : indices) out.push_back({"", i});
  }
  return out;
}

// The key path up to step n, as written in errors.
std::string shown(const std::vector<Step>& steps, std::size_t n) {
  std::string s;
  for (std::size_t k = 0; k <= n; ++k)
    s += steps[k].index >= 0 ? "." + std::to_string(steps[k].index) : (k ? "." : "") + steps[k].key;
  return s;
}

}  // namespace

void set_scene_value(toml::table& root, const std::string& key, toml::node&& value) {
  const std::vector<Step> steps = steps_of(key);
  toml::node* node = &root;
  for (std::size_t n = 0; n < steps.size(); ++n) {
    const Step& s = steps[n];
    const bool last = n + 1 == steps.size();
    if (s.index < 0) {
      toml::table* t = node->as_table();
      if (!t) throw SceneError(shown(steps, n - 1) + " is not a table");
      if (last) {
        t->insert_or_assign(s.key, std::move(value));
        return;
      }
      if (!t->contains(s.key)) {
        if (steps[n + 1].index >= 0) throw SceneError("the scene has no array " + shown(steps, n));
        t->insert(s.key, toml::table{});
      }
      node = t->get(s.key);
    } else {
      toml::array* a = node->as_array();
      if (!a) throw SceneError(shown(steps, n - 1) + " is not an array");
      if (static_cast<std::size_t>(s.index) >= a->size())
        throw SceneError(shown(steps, n - 1) + " has " + std::to_string(a->size()) + " entries");
      if (last) {
        a->replace(a->cbegin() + s.index, std::move(value));
        return;
      }
      node = a->get(static_cast<std::size_t>(s.index));
    }
  }
}

void apply_assignment(toml::table& root, const std::string& assignment) {
  const std::string where = "--set " + assignment + ": ";
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) throw SceneError(where + "expected KEY=VALUE (integrator.dt=5e-5)");
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  if (text.find_first_of("\r\n") != std::string::npos) throw SceneError(where + "the value must be one line");
  toml::table parsed;
  bool is_toml = false;
  try {
    parsed = toml::parse("v = " + text);
    is_toml = parsed.size() == 1 && parsed.contains("v");
  } catch (const toml::parse_error&) {
  }
  try {
    // A copy: toml++ copies no source region, so an error does not cite line 1 of the file.
    toml::table value = parsed;
    if (is_toml) set_scene_value(root, key, std::move(*value.get("v")));
    else set_scene_value(root, key, toml::value<std::string>(text));
  } catch (const SceneError& e) {
    throw SceneError(where + e.what());
  }
}

}  // namespace dem
