#include "cairn/bt_executive/executive.hpp"

#include <cctype>
#include <sstream>
#include <stdexcept>

#include "cairn/bt_executive/xml_loader.hpp"

namespace cairn::bt {

std::string_view toString(Executive::State s) {
  switch (s) {
    case Executive::State::Empty: return "empty";
    case Executive::State::Ready: return "ready";
    case Executive::State::Running: return "running";
    case Executive::State::Finished: return "finished";
    case Executive::State::Stopped: return "stopped";
  }
  return "?";
}

Executive::Executive(const NodeFactory& factory, Scheduler& scheduler) : factory_(factory), scheduler_(scheduler) {}

Executive::~Executive() {
  if (tree_) tree_->context().clearObservers();
}

void Executive::attach() {
  tree_->setScheduler(&scheduler_);
  tree_->addObserver([this](const TransitionEvent& e) {
    if (events_.size() >= capacity_) {
      ++dropped_;
      return;
    }
    events_.push_back({e.step, e.time.count(), e.uid, e.old_status, e.new_status});
  });
}

void Executive::load(const std::string& file, const std::string& tree_id) {
  LoadOptions o;
  o.main_tree = tree_id;
  auto fresh = std::make_unique<Tree>(loadTreeFromFile(factory_, file, o));  // throws: current tree untouched
  if (tree_) tree_->haltTree();
  tree_ = std::move(fresh);
  file_ = file;
  tree_id_ = tree_->id();  // the ID the loader chose (main_tree_to_execute or the only tree)
  attach();
  state_ = State::Ready;
  last_ = NodeStatus::IDLE;
}

void Executive::switchTree(const std::string& tree_id) {
  if (file_.empty()) throw std::logic_error("no tree file loaded");
  const bool was_running = state_ == State::Running;
  load(file_, tree_id);
  if (was_running) start();
}

bool Executive::start() {
  if (!tree_) return false;
  if (state_ == State::Finished || state_ == State::Stopped) tree_->haltTree();
  state_ = State::Running;
  return true;
}

void Executive::stop() {
  if (!tree_) return;
  tree_->haltTree();
  state_ = State::Stopped;
  last_ = NodeStatus::IDLE;
}

NodeStatus Executive::tick() {
  if (state_ != State::Running || !tree_) return last_;
  last_ = tree_->tickOnce();
  if (last_ != NodeStatus::RUNNING) state_ = State::Finished;
  return last_;
}

namespace {
void jsonString(std::ostringstream& os, std::string_view s) {
  os << '"';
  for (char c : s) {
    switch (c) {
      case '"': os << "\\\""; break;
      case '\\': os << "\\\\"; break;
      case '\n': os << "\\n"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          os << buf;
        } else {
          os << c;
        }
    }
  }
  os << '"';
}
}  // namespace

std::string Executive::statusJson() const {
  std::ostringstream os;
  os << "{\"tree\":";
  jsonString(os, tree_id_);
  os << ",\"file\":";
  jsonString(os, file_);
  os << ",\"state\":\"" << toString(state_) << "\",\"step\":" << (tree_ ? tree_->context().step() : 0)
     << ",\"status\":\"" << toString(last_) << "\",\"nodes\":[";
  if (tree_) {
    bool first = true;
    for (const auto& n : tree_->nodes()) {
      os << (first ? "" : ",") << "{\"uid\":" << n->uid() << ",\"path\":";
      jsonString(os, n->path());
      os << ",\"status\":\"" << toString(n->status()) << "\"}";
      first = false;
    }
  }
  os << "]}";
  return os.str();
}

std::string Executive::eventsJson() {
  std::ostringstream os;
  os << "{\"tree\":";
  jsonString(os, tree_id_);
  os << ",\"dropped\":" << dropped_ << ",\"events\":[";
  for (std::size_t i = 0; i < events_.size(); ++i) {
    const auto& e = events_[i];
    os << (i ? "," : "") << "{\"step\":" << e.step << ",\"t_ns\":" << e.t_ns << ",\"uid\":" << e.uid
       << ",\"from\":\"" << toString(e.from) << "\",\"to\":\"" << toString(e.to) << "\"}";
  }
  os << "]}";
  events_.clear();
  dropped_ = 0;
  return os.str();
}

// ---- a small parser for exactly the snapshot format above (strings, integers, arrays, objects).
namespace {
class JsonReader {
 public:
  explicit JsonReader(std::string_view s) : s_(s) {}
  void ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  void expect(char c) {
    ws();
    if (i_ >= s_.size() || s_[i_] != c) fail(std::string("expected '") + c + "'");
    ++i_;
  }
  bool peek(char c) {
    ws();
    return i_ < s_.size() && s_[i_] == c;
  }
  std::string str() {
    expect('"');
    std::string out;
    while (i_ < s_.size() && s_[i_] != '"') {
      char c = s_[i_++];
      if (c == '\\') {
        if (i_ >= s_.size()) fail("bad escape");
        char e = s_[i_++];
        if (e == 'n') out += '\n';
        else if (e == 'u') {
          if (i_ + 4 > s_.size()) fail("bad \\u escape");
          out += static_cast<char>(std::stoi(std::string(s_.substr(i_, 4)), nullptr, 16));
          i_ += 4;
        } else out += e;
      } else {
        out += c;
      }
    }
    expect('"');
    return out;
  }
  std::uint64_t num() {
    ws();
    std::size_t b = i_;
    while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
    if (b == i_) fail("expected a number");
    return std::stoull(std::string(s_.substr(b, i_ - b)));
  }
  [[noreturn]] void fail(const std::string& m) const {
    throw std::runtime_error("status json, offset " + std::to_string(i_) + ": " + m);
  }
  bool done() {
    ws();
    return i_ == s_.size();
  }

 private:
  std::string_view s_;
  std::size_t i_ = 0;
};
}  // namespace

StatusSnapshot parseStatusJson(std::string_view json) {
  StatusSnapshot snap;
  JsonReader r(json);
  r.expect('{');
  bool first = true;
  while (!r.peek('}')) {
    if (!first) r.expect(',');
    first = false;
    const std::string key = r.str();
    r.expect(':');
    if (key == "tree") snap.tree = r.str();
    else if (key == "file") (void)r.str();
    else if (key == "state") snap.state = r.str();
    else if (key == "status") (void)r.str();
    else if (key == "step") snap.step = r.num();
    else if (key == "nodes") {
      r.expect('[');
      bool fn = true;
      while (!r.peek(']')) {
        if (!fn) r.expect(',');
        fn = false;
        r.expect('{');
        std::uint64_t uid = 0;
        std::string path, status;
        bool fk = true;
        while (!r.peek('}')) {
          if (!fk) r.expect(',');
          fk = false;
          const std::string k = r.str();
          r.expect(':');
          if (k == "uid") uid = r.num();
          else if (k == "path") path = r.str();
          else if (k == "status") status = r.str();
          else r.fail("unknown node field '" + k + "'");
        }
        r.expect('}');
        auto st = statusFromString(status);
        if (!st) r.fail("bad status '" + status + "'");
        if (uid != snap.paths.size()) r.fail("node uids must be consecutive");
        snap.paths.push_back(path);
        snap.statuses.push_back(*st);
      }
      r.expect(']');
    } else {
      r.fail("unknown field '" + key + "'");
    }
  }
  r.expect('}');
  if (!r.done()) r.fail("trailing characters");
  return snap;
}

}  // namespace cairn::bt
