#include "cairn/bt_executive/blackboard.hpp"

namespace cairn::bt {

std::shared_ptr<Blackboard> Blackboard::create(std::shared_ptr<Blackboard> parent) {
  return std::shared_ptr<Blackboard>(new Blackboard(std::move(parent)));
}

Blackboard& Blackboard::root() {
  Blackboard* b = this;
  while (b->parent_) b = b->parent_.get();
  return *b;
}

void Blackboard::addRemap(std::string child_key, std::string parent_key) {
  std::lock_guard lock(mutex_);
  remaps_[std::move(child_key)] = std::move(parent_key);
}

std::pair<Blackboard*, std::string> Blackboard::resolveOwner(std::string_view key) {
  if (!key.empty() && key.front() == '@') return {&root(), std::string(key.substr(1))};
  std::string mapped;
  {
    std::lock_guard lock(mutex_);
    if (entries_.find(key) != entries_.end()) return {this, std::string(key)};
    if (auto it = remaps_.find(key); it != remaps_.end()) mapped = it->second;
  }
  if (!mapped.empty() && parent_) return parent_->resolveOwner(mapped);
  if (autoremap_ && parent_ && !key.empty() && key.front() != '_') return parent_->resolveOwner(key);
  return {this, std::string(key)};
}

std::shared_ptr<EntryBase> Blackboard::getEntry(std::string_view key) {
  auto [owner, k] = resolveOwner(key);
  std::lock_guard lock(owner->mutex_);
  auto it = owner->entries_.find(k);
  return it == owner->entries_.end() ? nullptr : it->second;
}

std::shared_ptr<EntryBase> Blackboard::declare(std::string_view key, const TypeInfo& type) {
  auto [owner, k] = resolveOwner(key);
  if (k.empty()) throw BlackboardError("empty blackboard key");
  std::lock_guard lock(owner->mutex_);
  auto it = owner->entries_.find(k);
  if (it != owner->entries_.end()) {
    if (it->second->type().index != type.index)
      throw BlackboardError("blackboard entry '" + k + "' has type " + it->second->type().name + ", not " +
                            type.name);
    return it->second;
  }
  auto e = type.make_entry(&type);
  owner->entries_.emplace(k, e);
  return e;
}

std::vector<std::pair<std::string, std::shared_ptr<EntryBase>>> Blackboard::localEntries() const {
  std::lock_guard lock(mutex_);
  return {entries_.begin(), entries_.end()};
}

}  // namespace cairn::bt
