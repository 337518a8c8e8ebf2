// A property named once and looked up once: what a stage keeps instead of
// calling WorldView::property(name) in every step.
//
// Property ids are dense and never reused: a registered property stays for the
// registry's life (PluginRegistry::remove keeps the types), and re-registering
// a name gives its old id. So the id found at a stage's first step is its id for
// every later step and every structure generation, and a stage may keep it.
// The lookup is lazy because a stage is constructed before the scene has
// registered every property it may read (a mod's types arrive with the mod).
#pragma once

#include <string_view>

#include "runtime/world.hpp"

namespace alloy {

class PropertyRef {
 public:
  constexpr explicit PropertyRef(std::string_view name) : name_(name) {}

  /// The id; InputError("unknown property") at the first use if it is not registered.
  PropertyId operator()(const WorldView& view) {
    if (id_ == kNoProperty) [[unlikely]]
      id_ = view.property(name_);
    return id_;
  }
  template <class T> ColumnView<T> column(const WorldView& view) { return view.column<T>((*this)(view)); }
  template <class T> ColumnWriter<T> writer(ResolverAccess& access) { return access.writer<T>((*this)(access)); }
  std::string_view name() const { return name_; }

 private:
  std::string_view name_;
  PropertyId id_ = kNoProperty;
};

}  // namespace alloy
