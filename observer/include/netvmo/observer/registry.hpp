// The one form of every registry in netvmo: the error models and estimators here, the transports
// and camera-stream kinds of the pipeline. A registry is a table of entries, each an object of an
// interface with
//   std::string_view name() const;         // what command lines, scenario files and summaries say
//   std::string_view description() const;  // one line for --help and messages
// and the operations of its kind; the table lists them in the order help texts do (the default
// first). Adding an entry: a file that defines a function returning it, and one line in its
// registry's table.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace netvmo::obs {

template <class Entry>
class Registry {
 public:
  /// `what`: the kind of entry, for messages ("error model", "estimator", ...).
  Registry(std::string what, std::vector<const Entry*> entries)
      : what_(std::move(what)), entries_(std::move(entries)) {}

  const std::string& what() const { return what_; }
  auto begin() const { return entries_.begin(); }
  auto end() const { return entries_.end(); }
  size_t size() const { return entries_.size(); }

  /// The entry of that name, or nullptr.
  const Entry* lookup(std::string_view name) const {
    for (const Entry* e : entries_)
      if (e->name() == name) return e;
    return nullptr;
  }
  /// The entry of that name. Throws std::invalid_argument "unknown <what> '<name>' (<names>)".
  const Entry& find(std::string_view name) const {
    if (const Entry* e = lookup(name)) return *e;
    throw std::invalid_argument("unknown " + what_ + " '" + std::string(name) + "' (" + names() +
                                ")");
  }
  /// The names in table order, joined by `separator` ("a, b, c").
  std::string names(std::string_view separator = ", ") const {
    std::string s;
    for (const Entry* e : entries_) {
      if (!s.empty()) s += separator;
      s += e->name();
    }
    return s;
  }

 private:
  std::string what_;
  std::vector<const Entry*> entries_;
};

}  // namespace netvmo::obs
