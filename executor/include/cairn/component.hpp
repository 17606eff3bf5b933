// Components: classes constructed from NodeOptions, registered by one macro in a shared library,
// loaded by name into a container.
//
//   class Talker : public cairn::Node { public: explicit Talker(const cairn::NodeOptions& o); ... };
//   CAIRN_REGISTER_COMPONENT(cairn_demo::Talker)
//
// A component library is built with cairn_add_component() (cmake/CairnCommon.cmake), which puts the .so
// and an index file (<lib>.components, one class name per line) into lib/cairn_components/ so that the
// container finds the library of a class without loading every library.
#ifndef CAIRN_COMPONENT_HPP
#define CAIRN_COMPONENT_HPP

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "cairn/node.hpp"

namespace cairn {

using ComponentFactory = std::function<std::shared_ptr<void>(const NodeOptions&)>;

class ComponentError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ComponentRegistry {
 public:
  static ComponentRegistry& instance();
  void add(const std::string& class_name, ComponentFactory f);
  /// nullptr if the class is not registered in this process (yet).
  const ComponentFactory* find(const std::string& class_name) const;
  std::vector<std::string> names() const;

 private:
  mutable std::mutex mu_;
  std::map<std::string, ComponentFactory> factories_;
};

struct ComponentRegistrar {
  ComponentRegistrar(const char* class_name, ComponentFactory f) {
    ComponentRegistry::instance().add(class_name, std::move(f));
  }
};

/// Finds and loads component libraries through their index files.
class ComponentLoader {
 public:
  /// Search path: $CAIRN_COMPONENT_PATH (colon-separated), <dir of the executable>/../lib/cairn_components,
  /// and <prefix>/lib/cairn_components for every prefix in $CMAKE_PREFIX_PATH and $COLCON_PREFIX_PATH.
  ComponentLoader();
  explicit ComponentLoader(std::vector<std::string> dirs) : dirs_(std::move(dirs)) {}
  /// The factory of `class_name`, loading its library if needed. Throws ComponentError naming the class
  /// (and the known classes, or dlerror()).
  const ComponentFactory& factory(const std::string& class_name);
  /// All classes listed in the index files: class -> library path.
  std::map<std::string, std::string> available() const;
  const std::vector<std::string>& dirs() const { return dirs_; }

 private:
  std::vector<std::string> dirs_;
  std::mutex mu_;
  std::map<std::string, void*> handles_;
};

}  // namespace cairn

#define CAIRN_COMPONENT_CONCAT_(a, b) a##b
#define CAIRN_COMPONENT_CONCAT(a, b) CAIRN_COMPONENT_CONCAT_(a, b)
#define CAIRN_REGISTER_COMPONENT(Class)                                                           \
  namespace {                                                                                     \
  const ::cairn::ComponentRegistrar CAIRN_COMPONENT_CONCAT(cairn_component_registrar_, __LINE__){ \
      #Class, [](const ::cairn::NodeOptions& o) -> std::shared_ptr<void> { return std::make_shared<Class>(o); }}; \
  }

#endif  // CAIRN_COMPONENT_HPP
