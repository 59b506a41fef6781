#include "mbot_slam_navigation/core/params.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace mbot {
namespace core {

ParamValue ParamValue::ofBool(bool v) {
  ParamValue p;
  p.type = Type::kBool;
  p.b = v;
  return p;
}
ParamValue ParamValue::ofInt(long v) {
  ParamValue p;
  p.type = Type::kInt;
  p.i = v;
  return p;
}
ParamValue ParamValue::ofDouble(double v) {
  ParamValue p;
  p.type = Type::kDouble;
  p.d = v;
  return p;
}
ParamValue ParamValue::ofString(const std::string& v) {
  ParamValue p;
  p.type = Type::kString;
  p.s = v;
  return p;
}
ParamValue ParamValue::ofList(std::vector<ParamValue> v) {
  ParamValue p;
  p.type = Type::kList;
  p.items = std::move(v);
  return p;
}
ParamValue ParamValue::ofMap(std::map<std::string, ParamValue> v) {
  ParamValue p;
  p.type = Type::kMap;
  p.fields = std::move(v);
  return p;
}

const ParamValue* ParamValue::get(const std::string& key) const {
  if (type != Type::kMap) return nullptr;
  const auto it = fields.find(key);
  return it == fields.end() ? nullptr : &it->second;
}

namespace {
std::string formatG(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
}  // namespace

std::string ParamValue::repr() const {
  switch (type) {
    case Type::kNone: return "None";
    case Type::kBool: return b ? "True" : "False";
    case Type::kInt: return std::to_string(i);
    case Type::kDouble: {
      std::string t = formatG(d);
      if (t.find_first_of(".en") == std::string::npos) t += ".0";
      return t;
    }
    case Type::kString: return "'" + s + "'";
    case Type::kList: {
      std::string t = "[";
      for (std::size_t k = 0; k < items.size(); ++k) t += (k ? ", " : "") + items[k].repr();
      return t + "]";
    }
    case Type::kMap: {
      std::string t = "{";
      bool first = true;
      for (const auto& [k, v] : fields) {
        t += (first ? "'" : ", '") + k + "': " + v.repr();
        first = false;
      }
      return t + "}";
    }
  }
  return "?";
}

namespace {
// difflib.SequenceMatcher(None, a, b).ratio(): 2 * matches / (len a + len b), the matches found as
// Ratcliff and Obershelp do (the longest common block, then recursively left and right of it).
int matchingCharacters(const std::string& a, std::size_t alo, std::size_t ahi, const std::string& b, std::size_t blo,
                       std::size_t bhi) {
  if (alo >= ahi || blo >= bhi) return 0;
  std::size_t best_i = alo, best_j = blo, best = 0;
  std::vector<std::size_t> prev(bhi - blo + 1, 0), cur(bhi - blo + 1, 0);
  for (std::size_t i = alo; i < ahi; ++i) {
    for (std::size_t j = blo; j < bhi; ++j) {
      const std::size_t k = j - blo + 1;
      cur[k] = a[i] == b[j] ? prev[k - 1] + 1 : 0;
      if (cur[k] > best) {  // strictly longer: the earliest longest block, as difflib
        best = cur[k];
        best_i = i + 1 - best;
        best_j = j + 1 - best;
      }
    }
    std::swap(prev, cur);
    std::fill(cur.begin(), cur.end(), 0);
  }
  if (best == 0) return 0;
  return static_cast<int>(best) + matchingCharacters(a, alo, best_i, b, blo, best_j) +
         matchingCharacters(a, best_i + best, ahi, b, best_j + best, bhi);
}

double similarity(const std::string& a, const std::string& b) {
  const std::size_t total = a.size() + b.size();
  return total == 0 ? 1.0 : 2.0 * matchingCharacters(a, 0, a.size(), b, 0, b.size()) / static_cast<double>(total);
}
}  // namespace

std::string nearestKey(const std::string& key, const std::vector<std::string>& known) {
  std::string best;
  double best_score = 0.75;  // difflib.get_close_matches' cutoff
  for (const auto& k : known) {
    const double s = similarity(key, k);
    if (s > best_score || (s == best_score && !best.empty() && k > best) || (s == best_score && best.empty())) {
      best_score = s;
      best = k;
    }
  }
  return best;
}

ParamReader::ParamReader(const ParamValue& values, const std::string& ns, Warn warn)
    : values_(values.type == ParamValue::Type::kMap ? values : ParamValue::ofMap()), warn_(std::move(warn)) {
  ns_ = ns;
  while (ns_.size() > 1 && ns_.back() == '/') ns_.pop_back();
  if (ns_.empty()) ns_ = "/";
}

std::string ParamReader::where(const std::string& key) const { return ns_ == "/" ? "/" + key : ns_ + "/" + key; }

namespace {
thread_local ParamCatalog* t_catalog = nullptr;
}  // namespace

ParamCatalog::ParamCatalog() {
  if (t_catalog) throw std::logic_error("ParamCatalog: one is already recording on this thread");
  t_catalog = this;
}
ParamCatalog::~ParamCatalog() { close(); }
void ParamCatalog::close() {
  if (t_catalog == this) t_catalog = nullptr;
}
ParamCatalog* ParamCatalog::current() { return t_catalog; }

void ParamCatalog::add(ParamDeclaration d) {
  for (const auto& e : declarations_) {
    if (e.ns == d.ns && e.key == d.key) return;
  }
  declarations_.push_back(std::move(d));
}

void ParamReader::declare(const std::string& key, const char* type, const ParamValue& fallback, const char* doc,
                          const std::string& bounds) {
  ParamCatalog* catalog = ParamCatalog::current();
  if (!catalog) return;
  ParamDeclaration d;
  d.ns = ns_;
  d.key = key;
  d.type = type;
  d.default_repr = fallback.repr();
  d.bounds = bounds;
  std::string text = doc ? doc : "";
  if (text.size() > 1 && text[0] == '[') {
    const auto close = text.find(']');
    if (close != std::string::npos) {
      d.unit = text.substr(1, close - 1);
      text = text.substr(close + 1);
      text.erase(0, text.find_first_not_of(' ') == std::string::npos ? text.size() : text.find_first_not_of(' '));
    }
  }
  d.meaning = text;
  catalog->add(std::move(d));
}

ParamValue ParamReader::lookup(const std::string& key, const ParamValue& fallback) {
  read_.insert(key);
  const ParamValue* v = values_.get(key);
  return v ? *v : fallback;
}

ParamValue ParamReader::raw(const std::string& key, const ParamValue& fallback, const char* doc, const char* type) {
  declare(key, type, fallback, doc);
  return lookup(key, fallback);
}

void ParamReader::ignored(const std::string& key, const char* why) {
  declare(key, "any", ParamValue(), (std::string("not used: ") + why).c_str());
  lookup(key, ParamValue());
}

double ParamReader::number(const std::string& key, double fallback, const char* doc, std::optional<double> minimum,
                           bool positive) {
  declare(key, "double", ParamValue::ofDouble(fallback), doc,
          positive ? "> 0" : minimum ? ">= " + formatG(*minimum) : "");
  const ParamValue v = lookup(key, ParamValue::ofDouble(fallback));
  if (!v.isNumber()) throw ParamError("parameter " + where(key) + " must be a number, got " + v.repr());
  const double x = v.number();
  if (positive && !(x > 0.0)) throw ParamError("parameter " + where(key) + " must be positive, got " + formatG(x));
  if (minimum && x < *minimum) {
    throw ParamError("parameter " + where(key) + " must be >= " + formatG(*minimum) + ", got " + formatG(x));
  }
  return x;
}

long ParamReader::integer(const std::string& key, long fallback, const char* doc, std::optional<long> minimum) {
  declare(key, "int", ParamValue::ofInt(fallback), doc, minimum ? ">= " + std::to_string(*minimum) : "");
  const ParamValue v = lookup(key, ParamValue::ofInt(fallback));
  long x;
  if (v.type == ParamValue::Type::kInt) x = v.i;
  else if (v.type == ParamValue::Type::kDouble && std::floor(v.d) == v.d && std::isfinite(v.d)) x = static_cast<long>(v.d);
  else throw ParamError("parameter " + where(key) + " must be an integer, got " + v.repr());
  if (minimum && x < *minimum) {
    throw ParamError("parameter " + where(key) + " must be >= " + std::to_string(*minimum) + ", got " + std::to_string(x));
  }
  return x;
}

bool ParamReader::boolean(const std::string& key, bool fallback, const char* doc) {
  declare(key, "bool", ParamValue::ofBool(fallback), doc);
  const ParamValue v = lookup(key, ParamValue::ofBool(fallback));
  if (v.type == ParamValue::Type::kBool) return v.b;
  if (v.type == ParamValue::Type::kInt && (v.i == 0 || v.i == 1)) return v.i == 1;  // gmapping's YAMLs write 0 and 1
  if (v.type == ParamValue::Type::kString) {
    std::string lower = v.s;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
    if (lower == "true" || lower == "false") return lower == "true";
  }
  throw ParamError("parameter " + where(key) + " must be true or false, got " + v.repr());
}

std::string ParamReader::string(const std::string& key, const std::string& fallback, const char* doc) {
  declare(key, "string", ParamValue::ofString(fallback), doc);
  const ParamValue v = lookup(key, ParamValue::ofString(fallback));
  if (v.type != ParamValue::Type::kString) throw ParamError("parameter " + where(key) + " must be a string, got " + v.repr());
  return v.s;
}

std::string ParamReader::frame(const std::string& key, const std::string& fallback, const char* doc) {
  declare(key, "frame", ParamValue::ofString(fallback), doc);
  const ParamValue v = lookup(key, ParamValue::ofString(fallback));
  if (v.type != ParamValue::Type::kString) throw ParamError("parameter " + where(key) + " must be a string, got " + v.repr());
  std::string value = v.s;
  if (!value.empty() && value[0] == '/') {
    const std::string stripped = value.substr(value.find_first_not_of('/') == std::string::npos ? value.size()
                                                                                                : value.find_first_not_of('/'));
    warn("parameter " + where(key) + ": frame id \"" + value + "\" has a leading \"/\", which tf2 does not accept; using \"" +
         stripped + "\"");
    value = stripped;
  }
  if (value.empty()) throw ParamError("parameter " + where(key) + ": empty frame id");
  return value;
}

double ParamReader::deprecated(const std::string& new_key, const std::string& old_key, double fallback, const char* doc) {
  declare(new_key, "double", ParamValue::ofDouble(fallback), doc);
  declare(old_key, "double", ParamValue(), ("deprecated name of " + new_key).c_str());
  if (has(new_key)) {
    if (has(old_key)) {
      read_.insert(old_key);
      warn("parameter " + where(old_key) + " is ignored because " + where(new_key) + " is set");
    }
    return number(new_key, fallback, doc);
  }
  if (has(old_key)) {
    warn("parameter " + where(old_key) + " is deprecated; use " + new_key);
    return number(old_key, fallback, doc);
  }
  return number(new_key, fallback, doc);
}

std::vector<std::string> ParamReader::reportUnknown(const std::set<std::string>& skip,
                                                    const std::map<std::string, std::string>& elsewhere) {
  std::vector<std::string> unknown;
  std::vector<std::string> candidates(read_.begin(), read_.end());
  candidates.insert(candidates.end(), skip.begin(), skip.end());
  for (const auto& [k, _] : elsewhere) candidates.push_back(k);
  for (const auto& [key, _] : values_.fields) {
    if (read_.count(key) || skip.count(key)) continue;
    unknown.push_back(key);
    const auto other = elsewhere.find(key);
    if (other != elsewhere.end()) {
      warn("parameter " + where(key) + " has no effect here: " + key + " is a parameter of " + other->second);
      continue;
    }
    const std::string guess = nearestKey(key, candidates);
    const auto guess_elsewhere = elsewhere.find(guess);
    if (!guess.empty() && guess_elsewhere != elsewhere.end() && !read_.count(guess)) {
      warn("unknown parameter " + where(key) + " (did you mean " + guess + "? that is a parameter of " +
           guess_elsewhere->second + ", not of this namespace); it is ignored");
    } else if (!guess.empty()) {
      warn("unknown parameter " + where(key) + " (did you mean " + guess + "?); it is ignored");
    } else {
      warn("unknown parameter " + where(key) + "; it is ignored");
    }
  }
  return unknown;
}

}  // namespace core
}  // namespace mbot
