#include "cairn/bt_executive/trace.hpp"

#include <charconv>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace cairn::bt {

std::string formatTransition(std::uint64_t step, std::string_view path, NodeStatus old_s, NodeStatus new_s) {
  std::string s = std::to_string(step);
  s += ' ';
  s += path;
  s += ' ';
  s += toString(old_s);
  s += " -> ";
  s += toString(new_s);
  return s;
}

namespace {
constexpr std::string_view kHeader = "# cairn-bt-trace 1";  // written by FileLogger, required by TraceReplay::read
}  // namespace

FileLogger::FileLogger(Tree& tree, std::ostream& os) : tree_(tree), os_(os) {
  os_ << kHeader << '\n';
  for (const auto& n : tree.nodes()) os_ << "N " << n->uid() << ' ' << n->path() << '\n';
  handle_ = tree.addObserver([this](const TransitionEvent& e) {
    os_ << "E " << e.step << ' ' << e.time.count() << ' ' << e.uid << ' ' << toString(e.old_status) << ' '
        << toString(e.new_status) << '\n';
  });
}

FileLogger::~FileLogger() {
  tree_.removeObserver(handle_);
  os_.flush();
}

void FileLogger::flush() { os_.flush(); }

namespace {
/// The next space-separated field of `ss` as an unsigned or signed integer, all of it.
template <class T>
bool field(std::istringstream& ss, T& out) {
  std::string tok;
  if (!(ss >> tok)) return false;
  const auto [end, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return ec == std::errc() && end == tok.data() + tok.size();
}
}  // namespace

TraceReplay TraceReplay::read(std::istream& is) {
  TraceReplay r;
  std::string line;
  std::size_t ln = 0;
  auto bad = [&](const std::string& m) { throw std::runtime_error("line " + std::to_string(ln) + ": " + m); };
  while (std::getline(is, line)) {
    ++ln;
    if (ln == 1) {
      if (line == kHeader) continue;
      if (line.rfind("# cairn-bt-trace ", 0) == 0)
        bad("unsupported trace version '" + line.substr(17) + "' (expected '" + std::string(kHeader) + "')");
      bad("not a cairn-bt trace (the first line must be '" + std::string(kHeader) + "')");
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ss(line);
    char kind = 0;
    ss >> kind;
    if (kind == 'N') {
      std::uint32_t uid;
      std::string path;
      if (!field(ss, uid) || !std::getline(ss >> std::ws, path) || path.empty()) bad("bad node record");
      if (uid != r.paths_.size()) bad("node ids must be consecutive from 0");
      r.paths_.push_back(path);
    } else if (kind == 'E') {
      RecordedTransition t{};
      std::string o, n, extra;
      if (!field(ss, t.step) || !field(ss, t.time_ns) || !field(ss, t.uid) || !(ss >> o >> n))
        bad("bad event record (expected E <step> <time_ns> <uid> <OLD> <NEW>)");
      if (ss >> extra) bad("bad event record: unexpected '" + extra + "' after the new status");
      if (t.time_ns < 0) bad("negative time " + std::to_string(t.time_ns));
      auto os = statusFromString(o), ns = statusFromString(n);
      if (!os || !ns) bad("bad status");
      if (t.uid >= r.paths_.size()) bad("event for unknown node " + std::to_string(t.uid));
      if (!r.events_.empty() && t.step < r.events_.back().step) bad("steps must not decrease");
      t.old_status = *os;
      t.new_status = *ns;
      r.events_.push_back(t);
    } else {
      bad("unknown record '" + std::string(1, kind) + "'");
    }
  }
  if (is.bad()) throw std::runtime_error("line " + std::to_string(ln + 1) + ": read error");
  if (ln == 0) throw std::runtime_error("line 1: empty file, not a cairn-bt trace (expected '" + std::string(kHeader) + "')");
  return r;
}

std::vector<NodeStatus> TraceReplay::statusesAfter(std::uint64_t step) const {
  std::vector<NodeStatus> s(paths_.size(), NodeStatus::IDLE);
  for (const auto& e : events_) {
    if (e.step > step) break;
    s[e.uid] = e.new_status;
  }
  return s;
}

std::string renderTree(const std::vector<std::string>& paths, const std::vector<NodeStatus>& statuses, bool color) {
  std::string out;
  for (std::size_t i = 0; i < paths.size(); ++i) {
    const std::string& p = paths[i];
    std::size_t depth = 0;
    std::size_t last = 0;
    for (std::size_t k = 0; k < p.size(); ++k)
      if (p[k] == '/') {
        ++depth;
        last = k + 1;
      }
    const NodeStatus st = i < statuses.size() ? statuses[i] : NodeStatus::IDLE;
    out.append(depth * 2, ' ');
    out += p.substr(last);
    out += "  ";
    if (color) {
      const char* c = st == NodeStatus::RUNNING   ? "\033[33m"
                       : st == NodeStatus::SUCCESS ? "\033[32m"
                       : st == NodeStatus::FAILURE ? "\033[31m"
                       : st == NodeStatus::SKIPPED ? "\033[36m"
                                                   : "\033[2m";
      out += c;
      out += toString(st);
      out += "\033[0m";
    } else {
      out += toString(st);
    }
    out += '\n';
  }
  return out;
}

}  // namespace cairn::bt
