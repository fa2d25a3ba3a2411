#pragma once
// Reading YAML maps with key tracking: every key asked for is "known"; finish() rejects the
// first key nobody asked for with "<file>: <key.path>: unknown key (valid keys: ...)".
// Type and range errors raise ConfigError naming the file and key path.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "lcmloc/app/config.hpp"

namespace lcmloc::app {

namespace yaml_detail {
inline std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < v.size(); ++i) out += (i ? sep : "") + v[i];
  return out;
}
inline std::string nodeText(const YAML::Node& n) {
  if (n.IsScalar()) return "'" + n.Scalar() + "'";
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "null";
}

template <typename T> inline const char* typeName();
template <> inline const char* typeName<double>() { return "a number"; }
template <> inline const char* typeName<int>() { return "an integer"; }
template <> inline const char* typeName<int64_t>() { return "an integer"; }
template <> inline const char* typeName<uint64_t>() { return "a non-negative integer"; }
template <> inline const char* typeName<bool>() { return "true or false"; }
template <> inline const char* typeName<std::string>() { return "a string"; }

/// Reads the keys of one YAML map; finish() rejects keys that were never asked for.
class KeyReader {
 public:
  KeyReader(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
    if (node_ && !node_.IsNull() && !node_.IsMap())
      throw ConfigError(file_, path_, "expected a map, got " + nodeText(node_));
    rejectDuplicateKeys();
  }

  std::string keyPath(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const std::string& file() const { return file_; }

  /// The child node (invalid when absent); marks the key as known.
  YAML::Node child(const std::string& key) {
    known_.push_back(key);
    if (!node_ || !node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
    return node_[key];
  }

  template <typename T>
  void get(const std::string& key, T& out) {
    YAML::Node n = child(key);
    if (n) out = convert<T>(n, keyPath(key));
  }

  template <typename T>
  void get(const std::string& key, T& out, T lo, T hi, const char* what = nullptr) {
    YAML::Node n = child(key);
    if (!n) return;
    T v = convert<T>(n, keyPath(key));
    if (v < lo || v > hi) {
      std::ostringstream os;
      os << "value " << v << " out of range [" << lo << ", " << hi << "]";
      if (what) os << " (" << what << ")";
      throw ConfigError(file_, keyPath(key), os.str());
    }
    out = v;
  }

  /// Fixed-size vector of numbers, each within [lo, hi].
  template <typename V>
  void getVector(const std::string& key, V& out, double lo, double hi) {
    YAML::Node n = child(key);
    if (!n) return;
    const std::string kp = keyPath(key);
    if (!n.IsSequence() || n.size() != static_cast<std::size_t>(out.size()))
      throw ConfigError(file_, kp, "expected a list of " + std::to_string(out.size()) +
                                       " numbers, got " + nodeText(n));
    for (std::size_t i = 0; i < n.size(); ++i) {
      double v = convert<double>(n[i], kp + "[" + std::to_string(i) + "]");
      if (v < lo || v > hi) {
        std::ostringstream os;
        os << "value " << v << " out of range [" << lo << ", " << hi << "]";
        throw ConfigError(file_, kp + "[" + std::to_string(i) + "]", os.str());
      }
      out[static_cast<Eigen::Index>(i)] = v;
    }
  }

  void getStrings(const std::string& key, std::vector<std::string>& out) {
    YAML::Node n = child(key);
    if (!n) return;
    const std::string kp = keyPath(key);
    if (n.IsNull()) { out.clear(); return; }
    if (!n.IsSequence()) throw ConfigError(file_, kp, "expected a list of strings, got " + nodeText(n));
    out.clear();
    for (std::size_t i = 0; i < n.size(); ++i)
      out.push_back(convert<std::string>(n[i], kp + "[" + std::to_string(i) + "]"));
  }

  /// A list of maps under key (absent or null: out unchanged): each map is read by
  /// item(KeyReader&, T&) into a default T, its unknown keys an error; shape names the map's keys
  /// for the error message of a key that is not a list.
  template <typename T, typename F>
  void getList(const std::string& key, std::vector<T>& out, const char* shape, F item) {
    YAML::Node n = child(key);
    if (!n || n.IsNull()) return;
    const std::string kp = keyPath(key);
    if (!n.IsSequence()) throw ConfigError(file_, kp, std::string("expected a list of ") + shape + ", got " + nodeText(n));
    out.clear();
    for (std::size_t i = 0; i < n.size(); ++i) {
      KeyReader r(n[i], file_, kp + "[" + std::to_string(i) + "]");
      T v{};
      item(r, v);
      r.finish();
      out.push_back(v);
    }
  }

  /// Throws for the first key that nobody asked for.
  void finish() const {
    if (!node_ || !node_.IsMap()) return;
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (std::find(known_.begin(), known_.end(), key) == known_.end())
        throw ConfigError(file_, keyPath(key), "unknown key (valid keys: " + join(known_) + ")");
    }
  }

  /// A key given twice in one map: yaml-cpp would silently read the first and drop the other.
  void rejectDuplicateKeys() const {
    if (!node_ || !node_.IsMap()) return;
    std::vector<std::string> keys;
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      if (std::find(keys.begin(), keys.end(), key) != keys.end()) {
        const YAML::Mark m = kv.first.Mark();
        throw ConfigError(file_, keyPath(key),
                          "given twice in one map" +
                              (m.is_null() ? std::string() : " (again at line " + std::to_string(m.line + 1) + ")"));
      }
      keys.push_back(key);
    }
  }

  template <typename T>
  T convert(const YAML::Node& n, const std::string& kp) const {
    if (!n.IsScalar()) throw ConfigError(file_, kp, std::string("expected ") + typeName<T>() + ", got " + nodeText(n));
    try {
      T v = n.as<T>();
      if constexpr (std::is_floating_point_v<T>) {
        if (!std::isfinite(v)) throw ConfigError(file_, kp, "expected a finite number, got " + nodeText(n));
      }
      return v;
    } catch (const YAML::BadConversion&) {
      throw ConfigError(file_, kp, std::string("expected ") + typeName<T>() + ", got " + nodeText(n));
    }
  }

 private:
  YAML::Node node_;
  std::string file_, path_;
  std::vector<std::string> known_;
};


}  // namespace yaml_detail

using yaml_detail::KeyReader;

}  // namespace lcmloc::app
