// The one reader of scene TOML: typed reads with defaults and limits, refusal of unknown keys,
// and SceneError messages that name the file, the field, the value, the reason and the line.
#pragma once

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "scene/scene_error.hpp"
#include "scene/scene_keys.hpp"

namespace dem {

// A value as the scene wrote it (strings quoted; cut at 60 characters), and a number.
inline std::string show(const toml::node& n) {
  std::ostringstream os;
  n.visit([&](auto&& v) {
    using T = std::decay_t<decltype(v)>;
    if constexpr (std::is_same_v<T, toml::value<std::string>>) os << '"' << v.get() << '"';
    else os << v;
  });
  std::string out = os.str();
  if (out.size() > 60) out = out.substr(0, 57) + "...";
  return out;
}

inline std::string show(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

// A TOML table being read: remembers the keys used so that unknown keys can be refused.
class Tab {
 public:
  Tab(const toml::table& t, std::string path, const std::string& file)
      : t_(t), path_(std::move(path)), file_(file), known_(scene_keys(path_)) {}

  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  [[noreturn]] void fail(const std::string& key, const std::string& value, const std::string& why) const {
    std::string msg = file_ + ": " + field(key);
    if (!value.empty()) msg += " = " + value;
    msg += ": " + why;
    if (auto n = t_.get(key)) {
      const auto& src = n->source();
      if (src.begin.line) msg += " (line " + std::to_string(src.begin.line) + ")";
    }
    throw SceneError(msg);
  }

  bool has(const std::string& key) const { return t_.contains(key); }

  const toml::node* node(const std::string& key) {
    // A key the reader asks for is one check_scene_keys lets through (scene_keys.cpp).
    if (known_ && std::find(known_->begin(), known_->end(), key) == known_->end())
      throw std::logic_error("scene reader: " + field(key) + " is not among the keys of scene_keys.cpp");
    used_.insert(key);
    return t_.get(key);
  }

  double num(const std::string& key, const double* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    double v;
    if (auto i = n->as_integer()) v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point()) v = f->get();
    else fail(key, show(*n), "expected a number");
    if (!std::isfinite(v)) fail(key, show(*n), "must be a finite number");
    return v;
  }
  double num(const std::string& key, double def) { return num(key, &def); }
  double positive(const std::string& key, const double* def = nullptr) {
    const double v = num(key, def);
    if (!(v > 0)) fail(key, show(v), "must be > 0");
    return v;
  }
  double positive(const std::string& key, double def) { return positive(key, &def); }
  double non_negative(const std::string& key, double def) {
    const double v = num(key, &def);
    if (v < 0) fail(key, show(v), "must be >= 0");
    return v;
  }
  long integer(const std::string& key, const long* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    if (auto i = n->as_integer()) return static_cast<long>(i->get());
    fail(key, show(*n), "expected an integer");
  }
  long integer(const std::string& key, long def) { return integer(key, &def); }
  bool boolean(const std::string& key, bool def) {
    const toml::node* n = node(key);
    if (!n) return def;
    if (auto b = n->as_boolean()) return b->get();
    fail(key, show(*n), "expected true or false");
  }
  std::string str(const std::string& key, const std::string* def = nullptr) {
    const toml::node* n = node(key);
    if (!n) {
      if (def) return *def;
      fail(key, "", "required value is missing");
    }
    if (auto s = n->as_string()) return s->get();
    fail(key, show(*n), "expected a string");
  }
  std::string str(const std::string& key, const std::string& def) { return str(key, &def); }
  std::string choice(const std::string& key, const std::vector<std::string>& allowed,
                     const std::string* def = nullptr) {
    const std::string v = str(key, def);
    if (std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(key, '"' + v + '"', "must be one of: " + list);
    }
    return v;
  }
  std::string choice(const std::string& key, const std::vector<std::string>& allowed, const std::string& def) {
    return choice(key, allowed, &def);
  }
  // [x, y] of finite numbers.
  void vec2(const std::string& key, double& x, double& y, bool required = true) {
    const toml::node* n = node(key);
    if (!n) {
      if (required) fail(key, "", "required value is missing");
      return;
    }
    auto a = n->as_array();
    if (!a || a->size() != 2) fail(key, show(*n), "expected an array of two numbers [x, y]");
    double v[2];
    for (int k = 0; k < 2; ++k) {
      const toml::node& e = *a->get(k);
      if (auto i = e.as_integer()) v[k] = static_cast<double>(i->get());
      else if (auto f = e.as_floating_point()) v[k] = f->get();
      else fail(key, show(*n), "expected an array of two numbers [x, y]");
      if (!std::isfinite(v[k])) fail(key, show(*n), "must hold finite numbers");
    }
    x = v[0];
    y = v[1];
  }
  const toml::table* table(const std::string& key, bool required) {
    const toml::node* n = node(key);
    if (!n) {
      if (required) fail(key, "", "required table is missing");
      return nullptr;
    }
    if (auto t = n->as_table()) return t;
    fail(key, show(*n), "expected a table [" + field(key) + "]");
  }
  const toml::array* array_of_tables(const std::string& key) {
    const toml::node* n = node(key);
    if (!n) return nullptr;
    auto a = n->as_array();
    if (!a || !a->is_array_of_tables()) fail(key, show(*n), "expected an array of tables [[" + field(key) + "]]");
    return a;
  }
  // Refuses keys that were never asked for: unknown ones (check_scene_keys refused them first),
  // and known ones this table does not read (fill.s of a list fill).
  void finish() const {
    for (const auto& [k, v] : t_) {
      const std::string key(k.str());
      if (used_.count(key)) continue;
      if (known_ && std::find(known_->begin(), known_->end(), key) != known_->end())
        fail(key, show(v), path_ == "fill" ? "unknown key for a fill of this type" : "unknown key");
      fail(key, "", unknown_key_reason(path_, key));
    }
  }
  // A number with a default; `positive`: > 0, `non_negative`: >= 0; magnitude at most 1e15.
  double bounded(const std::string& key, double def, bool positive, bool non_negative = false) {
    const toml::node* n = node(key);
    if (!n) return def;
    double v;
    if (auto i = n->as_integer()) v = static_cast<double>(i->get());
    else if (auto f = n->as_floating_point()) v = f->get();
    else fail(key, show(*n), "expected a number");
    if (!std::isfinite(v) || std::abs(v) > 1e15) fail(key, show(*n), "must be a finite number of magnitude <= 1e15");
    if (positive && !(v > 0)) fail(key, show(v), "must be > 0");
    if (non_negative && v < 0) fail(key, show(v), "must be >= 0");
    return v;
  }
  // An array of finite numbers >= 0 (at most 10000), sorted; the default when absent.
  std::vector<double> numbers(const std::string& key, const std::vector<double>& def) {
    const toml::node* n = node(key);
    if (!n) return def;
    auto a = n->as_array();
    if (!a) fail(key, show(*n), "expected an array of numbers");
    if (a->size() > 10000) fail(key, "", "more than 10000 entries");
    std::vector<double> out;
    for (const auto& e : *a) {
      double v;
      if (auto i = e.as_integer()) v = static_cast<double>(i->get());
      else if (auto f = e.as_floating_point()) v = f->get();
      else fail(key, show(*n), "expected an array of numbers");
      if (!(v >= 0) || !std::isfinite(v)) fail(key, show(*n), "values must be finite and >= 0");
      out.push_back(v);
    }
    std::sort(out.begin(), out.end());
    return out;
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  const std::vector<std::string>* known_;  // nullptr: keys the scene names ([materials])
  std::set<std::string> used_;
};


}  // namespace dem
