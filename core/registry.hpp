// A registry of named factories (models, integrators) with the metadata `list` and `describe`
// print. Entries are registered explicitly by each layer's register_*() function rather than
// by static initialisers, which a static library's linker would silently drop.
#pragma once

#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "core/params.hpp"

namespace stiffbench {

template <class Product, class Info>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Product>(const Params&)>;
  struct Entry {
    Info info;  // has at least `std::string name`
    std::vector<ParamSpec> params;
    Factory make;
    bool built_in = true;  // false: added from outside the library (register_model)
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  void add(Entry entry) {
    if (find(entry.info.name))
      throw std::logic_error(kind_ + " '" + entry.info.name + "' registered twice");
    entries_.push_back(std::move(entry));
  }

  // Replaces the entry of the same name, or adds it.
  void add_or_replace(Entry entry) {
    for (auto& e : entries_)
      if (e.info.name == entry.info.name) {
        e = std::move(entry);
        return;
      }
    entries_.push_back(std::move(entry));
  }

  const Entry* find(const std::string& name) const {
    for (const auto& e : entries_)
      if (e.info.name == name) return &e;
    return nullptr;
  }

  // BadInput naming the unknown name and listing the known ones.
  const Entry& at(const std::string& name) const {
    if (const Entry* e = find(name)) return *e;
    throw BadInput("unknown " + kind_ + " '" + name + "'" + did_you_mean(name, names()) +
                   "; known: " + join(names()));
  }

  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (const auto& e : entries_) out.push_back(e.info.name);
    return out;
  }

  const std::vector<Entry>& entries() const { return entries_; }
  const std::string& kind() const { return kind_; }

  // Creates `name` with its defaults overlaid by the user's keys it declares; those keys are
  // added to `consumed`. A declared key the factory never read is a programming error.
  std::unique_ptr<Product> create(const std::string& name, const Params& user,
                                  std::set<std::string>* consumed = nullptr) const {
    const Entry& e = at(name);
    const Params effective = resolve_params(e.params, user, consumed, kind_ + " '" + name + "'");
    auto product = e.make(effective);
    // The product carries the name it was created under, not its coefficients' name (one
    // tableau registered twice with different parameters is two methods).
    if constexpr (requires(Product & p) { p.set_name(name); })
      if (product) product->set_name(name);
    for (const auto& spec : e.params) {
      if (!effective.read_keys().count(spec.key)) {
        throw std::logic_error(kind_ + " '" + name + "' declares parameter '" + spec.key +
                               "' but never reads it");
      }
    }
    return product;
  }

  // "model 'kepler' takes e, gm" for error messages.
  std::string accepted_keys(const std::string& name) const {
    std::vector<std::string> keys;
    for (const auto& p : at(name).params) keys.push_back(p.key);
    return kind_ + " '" + name + "' takes " + (keys.empty() ? "no parameters" : join(keys));
  }

 private:
  std::string kind_;
  std::vector<Entry> entries_;
};

}  // namespace stiffbench
