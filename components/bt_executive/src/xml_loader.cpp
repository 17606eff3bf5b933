// BehaviorTree.CPP v4 XML loader. Three phases so that every port is typed and every blackboard key is a slot
// before the first tick:
//   A. parse XML into node specs, check IDs/ports/children/literals/scripts, collect blackboard declarations
//      (following SubTree remaps) and detect SubTree cycles;
//   B. create one typed entry per declared key (typed ports win over untyped uses; two types -> error);
//   C. construct nodes with ports bound to entries, bind scripts.
#include "cairn/bt_executive/xml_loader.hpp"

#include <tinyxml2.h>

#include <array>
#include <filesystem>
#include <map>
#include <set>

namespace cairn::bt {
namespace {

namespace fs = std::filesystem;
using tinyxml2::XMLDocument;
using tinyxml2::XMLElement;

constexpr std::array<std::string_view, 4> kPre = {"_failureIf", "_successIf", "_skipIf", "_while"};
constexpr std::array<std::string_view, 4> kPost = {"_onSuccess", "_onFailure", "_post", "_onHalted"};

std::string xmlError(const XMLDocument& doc) {
  std::string detail = doc.ErrorStr() ? doc.ErrorStr() : "";
  if (auto p = detail.find("Line number="); p != std::string::npos) {
    auto c = detail.find(": ", p);
    detail = c == std::string::npos ? std::string() : detail.substr(c + 2);
  }
  std::string m = std::string("XML error: ") + doc.ErrorName();
  if (!detail.empty()) m += " (" + detail + ")";
  return m;
}

struct Where {
  std::string file;
  int line = 0;
};

struct TreeDef {
  std::string id;
  const XMLElement* elem = nullptr;
  std::string file;
};

struct ModelPort {
  std::string name;
  PortDirection dir = PortDirection::Input;
  const TypeInfo* type = nullptr;  // nullptr: unknown type name -> untyped
  std::optional<std::string> def;
};

struct Spec {
  const NodeManifest* manifest = nullptr;
  Where where;
  std::string id, name, path;
  std::shared_ptr<Blackboard> bb;
  struct Port {
    const PortInfo* info = nullptr;
    bool has_literal = false;
    std::string literal;
    std::string key;  // non-empty: bound to this blackboard key
    std::shared_ptr<Script> script;
  };
  std::vector<Port> ports;
  std::array<std::shared_ptr<Script>, 4> pre{}, post{};
  std::vector<std::unique_ptr<Spec>> children;
};

struct Decl {
  const TypeInfo* type = nullptr;  // strong type, if any
  Where where;
};

struct LiteralInit {
  std::shared_ptr<Blackboard> bb;
  std::string key;
  std::string literal;
  Where where;
};

const TypeInfo* typeByName(std::string_view n) {
  if (n == "int" || n == "int32_t" || n == "std::int32_t") return &typeInfo<int>();
  if (n == "unsigned int" || n == "uint32_t" || n == "unsigned") return &typeInfo<unsigned>();
  if (n == "long" || n == "int64_t" || n == "long long" || n == "std::int64_t") return &typeInfo<std::int64_t>();
  if (n == "double") return &typeInfo<double>();
  if (n == "float") return &typeInfo<float>();
  if (n == "bool") return &typeInfo<bool>();
  if (n == "std::string" || n == "string" || n == "std::__cxx11::basic_string<char, std::char_traits<char>, "
                                                   "std::allocator<char> >")
    return &typeInfo<std::string>();
  return nullptr;
}

/// "{key}" -> key, "{=}" -> port name; returns false for literals.
bool blackboardKey(std::string_view v, std::string_view port, std::string& key) {
  if (v.size() >= 2 && v.front() == '{' && v.back() == '}') {
    std::string_view k = v.substr(1, v.size() - 2);
    key = k == "=" ? std::string(port) : std::string(k);
    return true;
  }
  return false;
}

class Loader {
 public:
  Loader(const NodeFactory& f, const LoadOptions& o) : f_(f), opts_(o) {}

  void loadFile(const std::string& path, const Where* from) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::path(path), ec);
    const std::string key = ec ? path : p.string();
    if (!loaded_.insert(key).second) return;
    auto doc = std::make_unique<XMLDocument>();
    if (!fs::exists(path)) {
      if (from) throw LoadError(from->file, from->line, "included file not found: " + path);
      throw LoadError(path, 0, "file not found");
    }
    if (doc->LoadFile(path.c_str()) != tinyxml2::XML_SUCCESS)
      throw LoadError(path, doc->ErrorLineNum(), xmlError(*doc));
    docs_.push_back(std::move(doc));
    parseDocument(*docs_.back(), path, fs::path(path).parent_path());
  }

  void loadText(std::string_view text, const std::string& name) {
    auto doc = std::make_unique<XMLDocument>();
    if (doc->Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS)
      throw LoadError(name, doc->ErrorLineNum(), xmlError(*doc));
    docs_.push_back(std::move(doc));
    parseDocument(*docs_.back(), name, fs::current_path());
  }

  std::vector<std::string> treeIds() const { return order_; }

  Tree build() {
    std::string main = opts_.main_tree.empty() ? main_attr_ : opts_.main_tree;
    if (main.empty()) {
      if (main_file_trees_.size() == 1) main = main_file_trees_.front();
      else if (order_.size() == 1) main = order_.front();
      else
        throw LoadError(main_file_, 1,
                        order_.empty() ? "no <BehaviorTree> found"
                                       : "several trees and no main_tree_to_execute; choose one (--tree ID)");
    }
    auto it = trees_.find(main);
    if (it == trees_.end()) throw LoadError(main_file_, 1, "no tree with ID '" + main + "'");

    Tree tree;
    tree.setId(main);
    auto root_bb = opts_.blackboard ? opts_.blackboard : Blackboard::create();
    tree.addBlackboard(root_bb);
    tree_ = &tree;
    std::vector<std::string> stack{main};
    auto root = instantiateTree(it->second, root_bb, "", stack);
    materialize();
    uid_ = 0;
    TreeNode* r = construct(*root, tree);
    tree.setRoot(r);
    return tree;
  }

 private:
  [[noreturn]] static void fail(const Where& w, const std::string& m) { throw LoadError(w.file, w.line, m); }
  static Where at(const std::string& file, const XMLElement* e) { return Where{file, e ? e->GetLineNum() : 0}; }

  void parseDocument(XMLDocument& doc, const std::string& file, const fs::path& dir) {
    const XMLElement* root = doc.RootElement();
    if (!root) throw LoadError(file, 1, "empty document");
    if (std::string_view(root->Name()) != "root") fail(at(file, root), "root element must be <root>");
    if (const char* fmt = root->Attribute("BTCPP_format"); fmt && std::string_view(fmt) != "4")
      fail(at(file, root), std::string("unsupported BTCPP_format=\"") + fmt + "\" (only 4)");
    const bool is_main = main_file_.empty();
    if (is_main) {
      main_file_ = file;
      if (const char* m = root->Attribute("main_tree_to_execute")) main_attr_ = m;
    }
    for (const XMLElement* e = root->FirstChildElement(); e; e = e->NextSiblingElement()) {
      std::string_view tag = e->Name();
      if (tag == "include") {
        const char* p = e->Attribute("path");
        if (!p) fail(at(file, e), "<include> needs a path attribute");
        if (e->Attribute("ros_pkg")) fail(at(file, e), "<include ros_pkg> is not supported");
        fs::path inc = fs::path(p).is_absolute() ? fs::path(p) : dir / p;
        Where w = at(file, e);
        loadFile(inc.string(), &w);
      } else if (tag == "BehaviorTree") {
        const char* id = e->Attribute("ID");
        if (!id || !*id) fail(at(file, e), "<BehaviorTree> needs an ID");
        if (trees_.count(id)) fail(at(file, e), std::string("duplicate BehaviorTree ID '") + id + "'");
        trees_[id] = TreeDef{id, e, file};
        order_.push_back(id);
        if (is_main) main_file_trees_.push_back(id);
      } else if (tag == "TreeNodesModel") {
        parseModel(e, file);
      } else {
        fail(at(file, e), "unexpected element <" + std::string(tag) + "> under <root>");
      }
    }
  }

  void parseModel(const XMLElement* model, const std::string& file) {
    for (const XMLElement* e = model->FirstChildElement(); e; e = e->NextSiblingElement()) {
      std::string_view tag = e->Name();
      if (tag != "Action" && tag != "Condition" && tag != "Control" && tag != "Decorator" && tag != "SubTree")
        fail(at(file, e), "unexpected element <" + std::string(tag) + "> in <TreeNodesModel>");
      const char* id = e->Attribute("ID");
      if (!id) fail(at(file, e), "<" + std::string(tag) + "> in <TreeNodesModel> needs an ID");
      std::vector<ModelPort> ports;
      for (const XMLElement* p = e->FirstChildElement(); p; p = p->NextSiblingElement()) {
        std::string_view pt = p->Name();
        ModelPort mp;
        if (pt == "input_port") mp.dir = PortDirection::Input;
        else if (pt == "output_port") mp.dir = PortDirection::Output;
        else if (pt == "inout_port") mp.dir = PortDirection::InOut;
        else fail(at(file, p), "unexpected element <" + std::string(pt) + "> in a node model");
        const char* n = p->Attribute("name");
        if (!n) fail(at(file, p), "port model needs a name");
        mp.name = n;
        if (const char* t = p->Attribute("type")) mp.type = typeByName(t);
        if (const char* d = p->Attribute("default")) mp.def = d;
        ports.push_back(std::move(mp));
      }
      if (tag == "SubTree") subtree_models_[id] = std::move(ports);
    }
  }

  // ------------------------------------------------------------------------------------------- phase A
  void declare(const std::shared_ptr<Blackboard>& bb, const std::string& key, const TypeInfo* type, bool weak,
               const Where& w) {
    if (key.empty() || key == "@") fail(w, "empty blackboard key");
    auto [owner, k] = bb->resolveOwner(key);
    if (auto existing = owner->getEntry(k)) {
      if (!weak && existing->type().index != type->index)
        fail(w, "type mismatch: blackboard entry '" + key + "' has type " + existing->type().name + ", port wants " +
                    type->name);
      return;
    }
    Decl& d = decls_[{owner, k}];
    if (weak) {
      if (d.where.file.empty()) d.where = w;
      return;
    }
    if (d.type && d.type->index != type->index)
      fail(w, "type mismatch: blackboard entry '" + key + "' is " + d.type->name + " at " + d.where.file + ":" +
                  std::to_string(d.where.line) + " and " + type->name + " here");
    d.type = type;
    d.where = w;
  }

  std::shared_ptr<Script> parseScript(std::string_view code, const std::string& attr, const Where& w,
                                      const std::shared_ptr<Blackboard>& bb) {
    std::shared_ptr<Script> s;
    try {
      s = std::make_shared<Script>(Script::parse(code, &f_.scriptEnums()));
    } catch (const ScriptError& e) {
      fail(w, "script in '" + attr + "', column " + std::to_string(e.column) + ": " + e.what());
    }
    for (const auto& v : s->variables())
      if (v.created || v.read) declare(bb, v.name, &typeInfo<Value>(), true, w);
    scripts_.push_back({s, bb, w, attr});
    return s;
  }

  std::unique_ptr<Spec> instantiateTree(const TreeDef& def, const std::shared_ptr<Blackboard>& bb,
                                        const std::string& parent_path, std::vector<std::string>& stack) {
    const XMLElement* first = def.elem->FirstChildElement();
    if (!first) fail(at(def.file, def.elem), "BehaviorTree '" + def.id + "' is empty");
    if (first->NextSiblingElement())
      fail(at(def.file, first->NextSiblingElement()), "BehaviorTree '" + def.id + "' must have exactly one root node");
    return instantiateNode(first, def.file, bb, parent_path, nodeName(first), stack);
  }

  static std::string nodeName(const XMLElement* e) {
    if (const char* n = e->Attribute("name"); n && *n) return n;
    std::string_view tag = e->Name();
    if ((tag == "Action" || tag == "Condition" || tag == "Control" || tag == "Decorator") && e->Attribute("ID"))
      return e->Attribute("ID");
    return std::string(tag);
  }

  std::unique_ptr<Spec> instantiateNode(const XMLElement* e, const std::string& file,
                                        const std::shared_ptr<Blackboard>& bb, const std::string& parent_path,
                                        const std::string& segment, std::vector<std::string>& stack) {
    auto spec = std::make_unique<Spec>();
    spec->where = at(file, e);
    spec->bb = bb;
    spec->name = nodeName(e);
    spec->path = parent_path.empty() ? segment : parent_path + "/" + segment;
    std::string_view tag = e->Name();
    const bool legacy = tag == "Action" || tag == "Condition" || tag == "Control" || tag == "Decorator";
    if (legacy) {
      const char* id = e->Attribute("ID");
      if (!id) fail(spec->where, "<" + std::string(tag) + "> needs an ID");
      spec->id = id;
    } else {
      spec->id = std::string(tag);
    }
    spec->manifest = f_.find(spec->id);
    if (!spec->manifest) fail(spec->where, "unknown node '" + spec->id + "'");
    if (spec->manifest->kind == NodeKind::SubTree) {
      instantiateSubTree(*spec, e, stack);
      return spec;
    }

    // Attributes: name, ID (legacy), pre/post conditions, ports.
    for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
      std::string_view an = a->Name();
      if (an == "name" || (legacy && an == "ID") || an == "_description" || an == "_uid" || an == "_fullpath")
        continue;
      bool handled = false;
      for (std::size_t i = 0; i < 4; ++i) {
        if (an == kPre[i]) {
          spec->pre[i] = parseScript(a->Value(), std::string(an), spec->where, bb);
          handled = true;
        } else if (an == kPost[i]) {
          spec->post[i] = parseScript(a->Value(), std::string(an), spec->where, bb);
          handled = true;
        }
      }
      if (handled) continue;
      if (!spec->manifest->port(an))
        fail(spec->where, "node '" + spec->id + "' has no port '" + std::string(an) + "'");
    }
    for (const PortInfo& p : spec->manifest->ports) {
      Spec::Port sp;
      sp.info = &p;
      const char* v = e->Attribute(p.name.c_str());
      std::optional<std::string> value = v ? std::optional<std::string>(v) : p.default_value;
      if (!value) {
        if (p.direction != PortDirection::Output)
          fail(spec->where, "node '" + spec->id + "' is missing required port '" + p.name + "'");
        spec->ports.push_back(std::move(sp));
        continue;
      }
      std::string key;
      if (blackboardKey(*value, p.name, key) || (p.literal_is_key && !(key = *value).empty())) {
        if (p.is_script) fail(spec->where, "port '" + p.name + "' must be a literal script, not a blackboard key");
        sp.key = key;
        declare(bb, key, p.type, p.type->dynamic, spec->where);
      } else {
        if (p.direction == PortDirection::Output)
          fail(spec->where, "output port '" + p.name + "' must be a blackboard key in braces, got '" + *value + "'");
        sp.has_literal = true;
        sp.literal = *value;
        if (p.is_script) {
          sp.script = parseScript(*value, p.name, spec->where, bb);
        } else if (!p.type->check_literal) {
          fail(spec->where, "port '" + p.name + "' of type " + p.type->name + " needs a blackboard key, got '" +
                                *value + "'");
        } else {
          std::string err;
          if (!p.type->check_literal(*value, err))
            fail(spec->where, "type mismatch in port '" + p.name + "' (" + p.type->name + "): " + err);
        }
      }
      spec->ports.push_back(std::move(sp));
    }

    // Children, with '#index' on siblings that share a name.
    std::vector<const XMLElement*> kids;
    for (const XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) kids.push_back(c);
    const int nk = static_cast<int>(kids.size());
    const auto& m = *spec->manifest;
    if (nk < m.min_children || (m.max_children >= 0 && nk > m.max_children)) {
      std::string want = m.min_children == m.max_children ? std::to_string(m.min_children)
                         : m.max_children < 0             ? "at least " + std::to_string(m.min_children)
                                                          : std::to_string(m.min_children) + " to " +
                                                                std::to_string(m.max_children);
      fail(spec->where, "node '" + spec->id + "' has " + std::to_string(nk) + " children, expected " + want);
    }
    std::vector<std::string> names;
    for (auto* c : kids) names.push_back(nodeName(c));
    for (std::size_t i = 0; i < kids.size(); ++i) {
      std::string seg = names[i];
      if (std::count(names.begin(), names.end(), names[i]) > 1) seg += "#" + std::to_string(i);
      spec->children.push_back(instantiateNode(kids[i], file, bb, spec->path, seg, stack));
    }
    return spec;
  }

  void instantiateSubTree(Spec& spec, const XMLElement* e, std::vector<std::string>& stack) {
    const char* id = e->Attribute("ID");
    if (!id) fail(spec.where, "<SubTree> needs an ID");
    if (e->FirstChildElement()) fail(spec.where, "<SubTree> must not have children");
    auto it = trees_.find(id);
    if (it == trees_.end()) fail(spec.where, std::string("unknown SubTree ID '") + id + "'");
    if (std::find(stack.begin(), stack.end(), id) != stack.end()) {
      std::string chain;
      for (auto& s : stack) chain += s + " -> ";
      fail(spec.where, "SubTree cycle: " + chain + id);
    }
    auto child_bb = Blackboard::create(spec.bb);
    tree_->addBlackboard(child_bb);
    const auto model_it = subtree_models_.find(id);
    const std::vector<ModelPort>* model = model_it == subtree_models_.end() ? nullptr : &model_it->second;
    std::set<std::string> seen;
    for (const tinyxml2::XMLAttribute* a = e->FirstAttribute(); a; a = a->Next()) {
      std::string_view an = a->Name();
      if (an == "ID" || an == "name" || an == "_description" || an == "_uid" || an == "_fullpath") continue;
      if (an == "_autoremap") {
        std::string_view v = a->Value();
        if (v != "true" && v != "false" && v != "1" && v != "0")
          fail(spec.where, "_autoremap must be true or false, got '" + std::string(v) + "'");
        child_bb->setAutoRemap(v == "true" || v == "1");
        continue;
      }
      bool condition = false;
      for (std::size_t i = 0; i < 4; ++i) {
        if (an == kPre[i]) spec.pre[i] = parseScript(a->Value(), std::string(an), spec.where, spec.bb);
        if (an == kPost[i]) spec.post[i] = parseScript(a->Value(), std::string(an), spec.where, spec.bb);
        condition = condition || an == kPre[i] || an == kPost[i];
      }
      if (condition) continue;
      if (!an.empty() && an.front() == '_')
        fail(spec.where, "attribute '" + std::string(an) + "' is not supported on <SubTree>");
      seen.insert(std::string(an));
      remapPort(spec, child_bb, std::string(an), a->Value(), model);
    }
    if (model) {
      for (const auto& mp : *model) {
        if (!seen.count(mp.name) && mp.def) remapPort(spec, child_bb, mp.name, *mp.def, model);
        if (mp.type) declare(child_bb, mp.name, mp.type, false, spec.where);
      }
    }
    stack.push_back(id);
    spec.children.push_back(instantiateTree(it->second, child_bb, spec.path, stack));
    stack.pop_back();
  }

  void remapPort(Spec& spec, const std::shared_ptr<Blackboard>& child_bb, const std::string& port,
                 const std::string& value, const std::vector<ModelPort>* model) {
    if (model) {
      bool known = false;
      for (auto& mp : *model) known = known || mp.name == port;
      if (!known) fail(spec.where, "SubTree model has no port '" + port + "'");
    }
    std::string key;
    if (blackboardKey(value, port, key)) {
      child_bb->addRemap(port, key);
    } else {
      literal_inits_.push_back({child_bb, port, value, spec.where});
      declare(child_bb, port, &typeInfo<Value>(), true, spec.where);
    }
  }

  // ------------------------------------------------------------------------------------------- phase B
  void materialize() {
    for (auto& [k, d] : decls_) {
      try {
        k.first->declare(k.second, d.type ? *d.type : typeInfo<Value>());
      } catch (const BlackboardError& e) {
        fail(d.where, e.what());
      }
    }
    for (auto& li : literal_inits_) {
      auto entry = li.bb->getEntry(li.key);
      try {
        entry->setFromString(li.literal);
      } catch (const ConversionError& e) {
        fail(li.where, "type mismatch in SubTree port '" + li.key + "': " + e.what());
      }
    }
    for (auto& s : scripts_) {
      try {
        s.script->bind(*s.bb);
      } catch (const ScriptError& e) {
        fail(s.where, "script in '" + s.attr + "', column " + std::to_string(e.column) + ": " + e.what());
      }
    }
  }

  // ------------------------------------------------------------------------------------------- phase C
  TreeNode* construct(const Spec& s, Tree& tree) {
    NodeConfig cfg;
    cfg.id = s.id;
    cfg.name = s.name;
    cfg.path = s.path;
    cfg.uid = uid_++;
    cfg.location = s.where.file + ":" + std::to_string(s.where.line);
    cfg.blackboard = s.bb;
    cfg.context = &tree.context();
    cfg.enums = &f_.scriptEnums();
    cfg.pre = s.pre;
    cfg.post = s.post;
    for (const auto& p : s.ports) {
      PortBinding b;
      b.info = p.info;
      b.has_literal = p.has_literal;
      b.literal = p.literal;
      b.script = p.script;
      if (!p.key.empty()) {
        b.entry = s.bb->getEntry(p.key);
        if (!b.entry) fail(s.where, "internal: blackboard entry '" + p.key + "' was not created");
      }
      cfg.ports.push_back(std::move(b));
    }
    TreeNode* node = nullptr;
    try {
      node = tree.addNode(s.manifest->create(cfg));
    } catch (const PortError& e) {
      fail(s.where, e.what());
    } catch (const ConversionError& e) {
      fail(s.where, e.what());
    } catch (const BlackboardError& e) {
      fail(s.where, e.what());
    } catch (const std::logic_error& e) {
      fail(s.where, e.what());
    }
    for (const auto& c : s.children) node->addChild(construct(*c, tree));
    if (std::string err = node->validateChildren(); !err.empty()) fail(s.where, err);
    return node;
  }

  struct PendingScript {
    std::shared_ptr<Script> script;
    std::shared_ptr<Blackboard> bb;
    Where where;
    std::string attr;
  };

  const NodeFactory& f_;
  LoadOptions opts_;
  std::vector<std::unique_ptr<XMLDocument>> docs_;
  std::set<std::string> loaded_;
  std::map<std::string, TreeDef> trees_;
  std::vector<std::string> order_, main_file_trees_;
  std::string main_file_, main_attr_;
  std::map<std::string, std::vector<ModelPort>> subtree_models_;
  std::map<std::pair<Blackboard*, std::string>, Decl> decls_;
  std::vector<LiteralInit> literal_inits_;
  std::vector<PendingScript> scripts_;
  Tree* tree_ = nullptr;
  std::uint32_t uid_ = 0;
};

}  // namespace

Tree loadTreeFromFile(const NodeFactory& factory, const std::string& path, const LoadOptions& options) {
  Loader l(factory, options);
  l.loadFile(path, nullptr);
  return l.build();
}

Tree loadTreeFromText(const NodeFactory& factory, std::string_view xml, const LoadOptions& options,
                      const std::string& filename) {
  Loader l(factory, options);
  l.loadText(xml, filename);
  return l.build();
}

std::vector<std::string> listTreeIds(const std::string& path) {
  static const NodeFactory f;
  Loader l(f, {});
  l.loadFile(path, nullptr);
  return l.treeIds();
}

}  // namespace cairn::bt
