// Reading a ROS parameter namespace the way the navigation stack does, but checked; ROS-free.
//
// ParamValue is what the parameter server holds (XmlRpc: none, bool, int, double, string, list,
// struct); the roscpp nodes convert XmlRpcValue into it, the Python binding converts dicts. Every
// key a node reads is declared with its default; what the user set but nobody reads is reported
// with the nearest known key (`controller_patiente` -> `controller_patience`), or with the
// namespace it belongs to when it is a known key of another one (`planner_frequency` in
// `local_costmap`). Wrong types name the key and its namespace (ParamError). Frame ids lose a
// leading `/` (tf2 rejects them) with one warning each. Warnings go to a callable.
//
// Each read carries the parameter's one line of meaning, its unit first in brackets
// ("[m/s] the fastest forward speed"); with a ParamCatalog alive, every reader records what it
// reads (key, type, default, bounds, unit, meaning): the generated reference pages (docs/nodes/)
// come from there, so a parameter's default and meaning are written once, in the call that reads it.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbot {
namespace core {

struct ParamValue {
  enum class Type { kNone, kBool, kInt, kDouble, kString, kList, kMap };
  Type type = Type::kNone;
  bool b = false;
  long i = 0;
  double d = 0.0;
  std::string s;
  std::vector<ParamValue> items;               ///< kList
  std::map<std::string, ParamValue> fields;    ///< kMap

  static ParamValue ofBool(bool v);
  static ParamValue ofInt(long v);
  static ParamValue ofDouble(double v);
  static ParamValue ofString(const std::string& v);
  static ParamValue ofList(std::vector<ParamValue> v = {});
  static ParamValue ofMap(std::map<std::string, ParamValue> v = {});
  bool isNumber() const { return type == Type::kInt || type == Type::kDouble; }
  double number() const { return type == Type::kInt ? static_cast<double>(i) : d; }
  /// The field `key` of a map, or nullptr.
  const ParamValue* get(const std::string& key) const;
  /// Python-like text for messages: True, 3, 0.5, 'wide', [1, 2], {'a': 1}.
  std::string repr() const;
};

/// A parameter whose value cannot be used; the message names the key and namespace.
class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

using Warn = std::function<void(const std::string&)>;

/// One parameter as a reader read it, for the reference pages.
struct ParamDeclaration {
  std::string ns;            ///< the reader's namespace, e.g. /move_base/local_costmap
  std::string key;
  std::string type;          ///< double, int, bool, string, frame, list, any
  std::string default_repr;  ///< Python-like, as ParamValue::repr
  std::string bounds;        ///< "> 0", ">= 0.5" or ""
  std::string unit;          ///< from the doc's leading "[unit]", or ""
  std::string meaning;       ///< the doc without its unit; "" when the read gave none
};

/// While one is alive, every ParamReader on this thread records its reads in it (the first read of
/// a namespace's key wins). Not nestable: a second one on the same thread throws std::logic_error.
class ParamCatalog {
 public:
  ParamCatalog();
  ~ParamCatalog();
  ParamCatalog(const ParamCatalog&) = delete;
  ParamCatalog& operator=(const ParamCatalog&) = delete;
  const std::vector<ParamDeclaration>& declarations() const { return declarations_; }
  /// The catalog alive on this thread, or nullptr.
  static ParamCatalog* current();
  void add(ParamDeclaration d);
  /// Stops recording (the declarations stay); the destructor does it too.
  void close();

 private:
  std::vector<ParamDeclaration> declarations_;
};

/// `warn`, or a callable that drops the text when `warn` is empty.
inline Warn orIgnore(const Warn& warn) {
  return warn ? warn : Warn([](const std::string&) {});
}

/// The known key closest in spelling to `key` (Python difflib's ratio, cutoff 0.75, as the rospy
/// nodes did), or "" when nothing is close.
std::string nearestKey(const std::string& key, const std::vector<std::string>& known);

/// Typed reads from one namespace's values (a map), remembering which keys were read. `ns` is only
/// used in messages (e.g. /move_base/local_costmap).
class ParamReader {
 public:
  ParamReader(const ParamValue& values, const std::string& ns, Warn warn);

  const std::string& ns() const { return ns_; }
  std::string where(const std::string& key) const;
  bool has(const std::string& key) const { return values_.get(key) != nullptr; }
  // `doc`: one line of meaning, the unit first in brackets: "[Hz] how often the loop runs".
  /// The value (marking the key read), or `fallback` when it is not set; `type` names what the
  /// caller accepts, for the reference pages.
  ParamValue raw(const std::string& key, const ParamValue& fallback, const char* doc, const char* type = "any");
  double number(const std::string& key, double fallback, const char* doc, std::optional<double> minimum = std::nullopt,
                bool positive = false);
  long integer(const std::string& key, long fallback, const char* doc, std::optional<long> minimum = std::nullopt);
  bool boolean(const std::string& key, bool fallback, const char* doc);
  std::string string(const std::string& key, const std::string& fallback, const char* doc);
  /// A frame id; a leading '/' is stripped with a warning; empty is an error.
  std::string frame(const std::string& key, const std::string& fallback, const char* doc);
  /// A key accepted for compatibility with the ROS tool and not used: read (so that it is not
  /// reported unknown) and listed on the reference page with `why`.
  void ignored(const std::string& key, const char* why);
  /// ROS's loadParameterWithDeprecation for numbers: the new name wins; the old one still works,
  /// with a warning.
  double deprecated(const std::string& new_key, const std::string& old_key, double fallback, const char* doc);
  /// Warns about every key set but never read, except `skip` (sub-namespaces handled elsewhere);
  /// `elsewhere` maps keys of other namespaces to where they belong. Returns the unknown keys.
  std::vector<std::string> reportUnknown(const std::set<std::string>& skip = {},
                                         const std::map<std::string, std::string>& elsewhere = {});
  void markRead(const std::string& key) { read_.insert(key); }
  const std::set<std::string>& readKeys() const { return read_; }
  ParamValue& values() { return values_; }
  const ParamValue& values() const { return values_; }
  void warn(const std::string& text) const {
    if (warn_) warn_(text);
  }

 private:
  ParamValue lookup(const std::string& key, const ParamValue& fallback);
  void declare(const std::string& key, const char* type, const ParamValue& fallback, const char* doc,
               const std::string& bounds = "");

  ParamValue values_;
  std::string ns_;
  Warn warn_;
  std::set<std::string> read_;
};

}  // namespace core
}  // namespace mbot
