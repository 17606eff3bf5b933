#include "cairn/bt_executive/factory.hpp"

#include <sstream>

namespace cairn::bt {

void registerBuiltinNodes(NodeFactory& f);

const PortInfo* NodeManifest::port(std::string_view name) const {
  for (const auto& p : ports)
    if (p.name == name) return &p;
  return nullptr;
}

NodeFactory::NodeFactory() { registerBuiltinNodes(*this); }

void NodeFactory::registerManifest(NodeManifest m) {
  if (m.id.empty()) throw std::invalid_argument("node ID must not be empty");
  for (const auto& p : m.ports)
    if (!p.type) throw std::invalid_argument("port '" + p.name + "' of " + m.id + " has no type");
  manifests_[m.id] = std::move(m);
}

const NodeManifest* NodeFactory::find(std::string_view id) const {
  auto it = manifests_.find(id);
  return it == manifests_.end() ? nullptr : &it->second;
}

std::vector<const NodeManifest*> NodeFactory::manifests() const {
  std::vector<const NodeManifest*> out;
  for (const auto& [k, m] : manifests_) out.push_back(&m);
  return out;
}

namespace {
std::string xmlEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}
}  // namespace

std::string writeTreeNodesModel(const NodeFactory& factory, bool include_builtins) {
  static const NodeFactory builtins;
  std::ostringstream os;
  os << "<root BTCPP_format=\"4\">\n  <TreeNodesModel>\n";
  for (const NodeManifest* m : factory.manifests()) {
    if (m->kind == NodeKind::SubTree) continue;
    if (!include_builtins && &factory != &builtins && builtins.find(m->id)) continue;
    os << "    <" << toString(m->kind) << " ID=\"" << xmlEscape(m->id) << "\"";
    if (m->ports.empty()) {
      os << "/>\n";
      continue;
    }
    os << ">\n";
    for (const auto& p : m->ports) {
      const char* tag = p.direction == PortDirection::Input    ? "input_port"
                        : p.direction == PortDirection::Output ? "output_port"
                                                               : "inout_port";
      os << "      <" << tag << " name=\"" << xmlEscape(p.name) << "\" type=\"" << xmlEscape(p.type->name) << "\"";
      if (p.default_value) os << " default=\"" << xmlEscape(*p.default_value) << "\"";
      os << ">" << xmlEscape(p.description) << "</" << tag << ">\n";
    }
    os << "    </" << toString(m->kind) << ">\n";
  }
  os << "  </TreeNodesModel>\n</root>\n";
  return os.str();
}

}  // namespace cairn::bt
