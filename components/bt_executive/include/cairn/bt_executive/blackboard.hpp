// Typed, hierarchical blackboard. Entries are created when a tree is loaded and nodes keep direct pointers to
// them, so ticking never looks up a key by string. Every entry has its own mutex, so async actions may read and
// write entries from executor threads while the tree ticks.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <string_view>
#include <typeindex>
#include <unordered_map>
#include <vector>

#include "cairn/bt_executive/value.hpp"

namespace cairn::bt {

class EntryBase;

/// Run-time description of a blackboard / port type.
struct TypeInfo {
  std::type_index index;
  std::string name;
  bool script_type;                                  ///< usable from scripts (bool, numbers, string, any)
  bool dynamic;                                      ///< the "any" type (Value): accepts every script value
  bool (*check_literal)(std::string_view, std::string& err);  ///< nullptr: no string conversion
  std::shared_ptr<EntryBase> (*make_entry)(const TypeInfo*);
};

template <class T>
const TypeInfo& typeInfo();

/// One typed blackboard slot.
class EntryBase {
 public:
  explicit EntryBase(const TypeInfo* t) : type_(t) {}
  virtual ~EntryBase() = default;
  EntryBase(const EntryBase&) = delete;
  EntryBase& operator=(const EntryBase&) = delete;

  const TypeInfo& type() const { return *type_; }
  bool hasValue() const { return sequence_.load(std::memory_order_acquire) != 0; }
  /// Incremented on every write; 0 = never written.
  std::uint64_t sequence() const { return sequence_.load(std::memory_order_acquire); }

  /// Script bridge; false if the entry holds no value or its type is not a script type.
  virtual bool getValue(Value& out) const = 0;
  /// Script bridge; false if `v` does not fit the entry's type.
  virtual bool setValue(const Value& v) = 0;
  /// Converts and stores a string literal; throws ConversionError.
  virtual void setFromString(std::string_view s) = 0;
  /// Copies the value of an entry of the same type (or via Value for script types); false if incompatible.
  virtual bool copyFrom(const EntryBase& other) = 0;
  virtual std::string toString() const = 0;

 protected:
  void bump() { sequence_.fetch_add(1, std::memory_order_acq_rel); }
  mutable std::mutex mutex_;

 private:
  const TypeInfo* type_;
  std::atomic<std::uint64_t> sequence_{0};
};

template <class T>
class TypedEntry final : public EntryBase {
 public:
  explicit TypedEntry(const TypeInfo* t) : EntryBase(t) {}

  /// Copies the value into `out`; false if never written.
  bool tryGet(T& out) const {
    std::lock_guard lock(mutex_);
    if (!has_) return false;
    out = value_;
    return true;
  }
  void set(const T& v) {
    {
      std::lock_guard lock(mutex_);
      value_ = v;
      has_ = true;
    }
    bump();
  }
  void set(T&& v) {
    {
      std::lock_guard lock(mutex_);
      value_ = std::move(v);
      has_ = true;
    }
    bump();
  }
  /// Runs `f(T&)` under the entry's lock (for in-place updates of large values).
  template <class F>
  void update(F&& f) {
    {
      std::lock_guard lock(mutex_);
      f(value_);
      has_ = true;
    }
    bump();
  }

  bool getValue(Value& out) const override {
    if constexpr (kScriptType<T>) {
      std::lock_guard lock(mutex_);
      if (!has_) return false;
      out = toValue(value_);
      return true;
    } else {
      (void)out;
      return false;
    }
  }
  bool setValue(const Value& v) override {
    if constexpr (kScriptType<T>) {
      T tmp{};
      if (!fromValue(v, tmp)) return false;
      set(std::move(tmp));
      return true;
    } else {
      (void)v;
      return false;
    }
  }
  void setFromString(std::string_view s) override {
    if constexpr (Convert<T>::available) {
      set(Convert<T>::fromString(s));
    } else {
      throw ConversionError("type " + type().name + " cannot be converted from a string");
    }
  }
  bool copyFrom(const EntryBase& other) override {
    if (auto* o = dynamic_cast<const TypedEntry<T>*>(&other)) {
      T tmp{};
      if (!o->tryGet(tmp)) return false;
      set(std::move(tmp));
      return true;
    }
    Value v;
    if (!other.getValue(v)) return false;
    return setValue(v);
  }
  std::string toString() const override {
    if constexpr (kScriptType<T>) {
      Value v;
      if (!getValue(v)) return "<unset>";
      return valueToString(v);
    } else {
      return hasValue() ? "<" + type().name + ">" : "<unset>";
    }
  }

 private:
  T value_{};
  bool has_ = false;
};

template <class T>
const TypeInfo& typeInfo() {
  static const TypeInfo info{
      std::type_index(typeid(T)),
      typeName<T>(),
      kScriptType<T>,
      std::is_same_v<T, Value>,
      Convert<T>::available ? +[](std::string_view s, std::string& err) -> bool {
        if constexpr (Convert<T>::available) {
          try {
            (void)Convert<T>::fromString(s);
            return true;
          } catch (const ConversionError& e) {
            err = e.what();
            return false;
          }
        } else {
          (void)s;
          (void)err;
          return false;
        }
      }
                            : nullptr,
      +[](const TypeInfo* self) -> std::shared_ptr<EntryBase> { return std::make_shared<TypedEntry<T>>(self); }};
  return info;
}

/// Errors of blackboard declaration / access through the string API (load time and user code, not ticks).
struct BlackboardError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A blackboard scope. The main tree owns the root scope; every SubTree instance gets a child scope whose keys
/// are private unless remapped to a parent key (`port="{parent_key}"`) or auto-remapped (`_autoremap="true"`).
/// Keys starting with '@' address the root scope directly; keys starting with '_' are never auto-remapped.
class Blackboard : public std::enable_shared_from_this<Blackboard> {
 public:
  static std::shared_ptr<Blackboard> create(std::shared_ptr<Blackboard> parent = nullptr);

  Blackboard* parent() const { return parent_.get(); }
  Blackboard& root();
  void addRemap(std::string child_key, std::string parent_key);
  void setAutoRemap(bool on) { autoremap_ = on; }
  bool autoRemap() const { return autoremap_; }

  /// Scope and key that own `key` after following remaps (load-time resolution).
  std::pair<Blackboard*, std::string> resolveOwner(std::string_view key);

  /// Entry for `key` following remaps; nullptr if none (string lookup: load time and user code only).
  std::shared_ptr<EntryBase> getEntry(std::string_view key);
  /// Creates the entry in the owning scope, or returns the existing one if its type matches; throws
  /// BlackboardError on a type mismatch.
  std::shared_ptr<EntryBase> declare(std::string_view key, const TypeInfo& type);
  template <class T>
  std::shared_ptr<TypedEntry<T>> declare(std::string_view key) {
    return std::static_pointer_cast<TypedEntry<T>>(declare(key, typeInfo<T>()));
  }

  /// Convenience string API (tests, tools, adapters; not for per-tick use).
  template <class T>
  void set(std::string_view key, const T& v) {
    auto e = getEntry(key);
    if (!e) e = declare(key, typeInfo<T>());
    if (auto* t = dynamic_cast<TypedEntry<T>*>(e.get())) {
      t->set(v);
    } else if (!e->setValue(toValue(v)) || !kScriptType<T>) {
      throw BlackboardError("blackboard entry '" + std::string(key) + "' has type " + e->type().name);
    }
  }
  template <class T>
  T get(std::string_view key) {
    auto e = getEntry(key);
    if (!e) throw BlackboardError("no blackboard entry '" + std::string(key) + "'");
    T out{};
    if (auto* t = dynamic_cast<TypedEntry<T>*>(e.get())) {
      if (t->tryGet(out)) return out;
      throw BlackboardError("blackboard entry '" + std::string(key) + "' is unset");
    }
    Value v;
    if (e->getValue(v) && fromValue(v, out)) return out;
    throw BlackboardError("blackboard entry '" + std::string(key) + "' (" + e->type().name + ") is unset or not a " +
                          typeName<T>());
  }

  /// Local entries (for dumps and the monitor).
  std::vector<std::pair<std::string, std::shared_ptr<EntryBase>>> localEntries() const;

 private:
  explicit Blackboard(std::shared_ptr<Blackboard> parent) : parent_(std::move(parent)) {}
  std::shared_ptr<Blackboard> parent_;
  mutable std::mutex mutex_;  // guards the maps (load time / string API only)
  std::map<std::string, std::shared_ptr<EntryBase>, std::less<>> entries_;
  std::map<std::string, std::string, std::less<>> remaps_;
  bool autoremap_ = false;
};

}  // namespace cairn::bt
