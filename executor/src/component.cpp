#include "cairn/component.hpp"
#include "cairn/data_files.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace cairn {

ComponentRegistry& ComponentRegistry::instance() {
  static ComponentRegistry r;
  return r;
}

void ComponentRegistry::add(const std::string& class_name, ComponentFactory f) {
  std::lock_guard l(mu_);
  factories_[class_name] = std::move(f);
}

const ComponentFactory* ComponentRegistry::find(const std::string& class_name) const {
  std::lock_guard l(mu_);
  auto it = factories_.find(class_name);
  return it == factories_.end() ? nullptr : &it->second;
}

std::vector<std::string> ComponentRegistry::names() const {
  std::lock_guard l(mu_);
  std::vector<std::string> out;
  for (const auto& [k, v] : factories_) out.push_back(k);
  return out;
}

ComponentLoader::ComponentLoader() {
  if (const char* env = std::getenv("CAIRN_COMPONENT_PATH")) {
    std::stringstream ss(env);
    std::string item;
    while (std::getline(ss, item, ':')) {
      if (!item.empty()) dirs_.push_back(item);
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) dirs_.push_back((exe.parent_path().parent_path() / "lib" / "cairn_components").string());
  for (const auto& d : prefix_paths("lib/cairn_components")) dirs_.push_back(d.string());
}

std::map<std::string, std::string> ComponentLoader::available() const {
  std::map<std::string, std::string> out;
  for (const auto& d : dirs_) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) continue;
    for (const auto& e : fs::directory_iterator(d, ec)) {
      const auto p = e.path();
      if (p.extension() != ".components") continue;
      const fs::path lib = p.parent_path() / p.stem();  // libfoo.so.components -> libfoo.so
      std::ifstream in(p);
      std::string line;
      while (std::getline(in, line)) {
        if (!line.empty() && line[0] != '#' && !out.count(line)) out[line] = lib.string();
      }
    }
  }
  return out;
}

const ComponentFactory& ComponentLoader::factory(const std::string& class_name) {
  if (const auto* f = ComponentRegistry::instance().find(class_name)) return *f;
  const auto avail = available();
  auto it = avail.find(class_name);
  if (it == avail.end()) {
    std::string known;
    for (const auto& [k, v] : avail) known += (known.empty() ? "" : ", ") + k;
    throw ComponentError("unknown component class '" + class_name + "' (known: " + (known.empty() ? "none" : known) +
                         ")");
  }
  {
    std::lock_guard l(mu_);
    if (!handles_.count(it->second)) {
      dlerror();
      void* h = dlopen(it->second.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!h) {
        const char* err = dlerror();
        throw ComponentError("cannot load component library " + it->second + ": " + (err ? err : "unknown error"));
      }
      handles_[it->second] = h;  // kept loaded: code of destroyed components may still be referenced
    }
  }
  if (const auto* f = ComponentRegistry::instance().find(class_name)) return *f;
  throw ComponentError("library " + it->second + " is indexed for '" + class_name +
                       "' but does not register it (missing CAIRN_REGISTER_COMPONENT?)");
}

}  // namespace cairn
