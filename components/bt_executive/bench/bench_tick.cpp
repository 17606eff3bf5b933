// Tick cost and blackboard reads (issue 8 "Performance"), with baselines measured in the same run:
//   - a minimal hand-written virtual-dispatch tree of the same shape (lower bound for any engine),
//   - blackboard reads by string key through a mutex-protected unordered_map<string, std::any> (the lookup a
//     string-keyed blackboard pays on every read; cairn resolves keys to typed slots at load time).
// Allocations per tick are counted with a replaced global operator new.
#include <benchmark/benchmark.h>

#include <any>
#include <atomic>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <new>
#include <sstream>
#include <unordered_map>

#include "cairn/bt_executive/factory.hpp"
#include "cairn/bt_executive/xml_loader.hpp"

static std::atomic<std::uint64_t> g_allocs{0};
void* operator new(std::size_t n) {
  g_allocs.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using namespace cairn::bt;

namespace {

// ---- the standard 1000-node tree: sequences and fallbacks (alternating by level), leaves alternate conditions
// and sync actions; children of fallbacks are wrapped in ForceFailure and fallbacks in ForceSuccess so that every
// node is ticked on every tick and nothing is RUNNING.
struct Gen {
  int nodes = 0;
  int leaf_counter = 0;
  void leaf(std::ostringstream& os) {
    ++nodes;
    os << (leaf_counter++ % 2 ? "<Ok/>" : "<Act/>");
  }
  void inner(std::ostringstream& os, int depth, bool seq, int branching) {
    if (depth == 0) return leaf(os);
    if (!seq) {
      ++nodes;
      os << "<ForceSuccess>";
    }
    ++nodes;
    os << (seq ? "<Sequence>" : "<Fallback>");
    for (int i = 0; i < branching; ++i) {
      if (!seq) {
        ++nodes;
        os << "<ForceFailure>";
      }
      inner(os, depth - 1, !seq, branching);
      if (!seq) os << "</ForceFailure>";
    }
    os << (seq ? "</Sequence>" : "</Fallback>");
    if (!seq) os << "</ForceSuccess>";
  }
};

std::string balancedTreeXml(int* node_count) {
  Gen g;
  std::ostringstream body;
  g.inner(body, 8, true, 2);  // depth 8, branching 2: 1021 nodes (256 leaves), counted in `nodes`
  *node_count = g.nodes;
  return "<root BTCPP_format=\"4\"><BehaviorTree ID=\"B\">" + body.str() + "</BehaviorTree></root>";
}

NodeFactory& factory() {
  static NodeFactory f = [] {
    NodeFactory f;
    f.registerSimpleCondition("Ok", [] { return true; });
    f.registerSimpleAction("Act", [] { return NodeStatus::SUCCESS; });
    return f;
  }();
  return f;
}

void BM_Tick_Balanced1000(benchmark::State& st) {
  int n = 0;
  ManualScheduler sched;  // outlives the tree
  Tree t = loadTreeFromText(factory(), balancedTreeXml(&n));
  t.setScheduler(&sched);
  t.tickOnce();
  std::uint64_t a0 = g_allocs.load();
  for (auto _ : st) benchmark::DoNotOptimize(t.tickOnce());
  st.counters["nodes"] = n;
  st.counters["allocs_per_tick"] = double(g_allocs.load() - a0) / double(st.iterations());
}
BENCHMARK(BM_Tick_Balanced1000);

void BM_Tick_Balanced1000_Observed(benchmark::State& st) {
  int n = 0;
  ManualScheduler sched;  // outlives the tree
  Tree t = loadTreeFromText(factory(), balancedTreeXml(&n));
  t.setScheduler(&sched);
  std::uint64_t events = 0;
  t.addObserver([&](const TransitionEvent&) { ++events; });
  t.tickOnce();
  std::uint64_t a0 = g_allocs.load(), e0 = events;
  for (auto _ : st) benchmark::DoNotOptimize(t.tickOnce());
  st.counters["events_per_tick"] = double(events - e0) / double(st.iterations());
  st.counters["allocs_per_tick"] = double(g_allocs.load() - a0) / double(st.iterations());
}
BENCHMARK(BM_Tick_Balanced1000_Observed);

// ---- baseline: minimal virtual-dispatch tree, same shape, no statuses/halting/events/blackboard.
struct BNode {
  virtual ~BNode() = default;
  virtual int tick() = 0;  // 1 success, 0 failure
  std::vector<std::unique_ptr<BNode>> kids;
};
struct BSeq : BNode {
  int tick() override {
    for (auto& k : kids)
      if (!k->tick()) return 0;
    return 1;
  }
};
struct BFb : BNode {
  int tick() override {
    for (auto& k : kids)
      if (k->tick()) return 1;
    return 0;
  }
};
struct BConst : BNode {
  int v;
  explicit BConst(int x) : v(x) {}
  int tick() override { return v; }
};
struct BForce : BNode {
  int v;
  explicit BForce(int x) : v(x) {}
  int tick() override {
    kids[0]->tick();
    return v;
  }
};
std::unique_ptr<BNode> baseline(int depth, bool seq, int branching, int& count) {
  if (depth == 0) {
    ++count;
    return std::make_unique<BConst>(1);
  }
  std::unique_ptr<BNode> n = seq ? std::unique_ptr<BNode>(new BSeq) : std::unique_ptr<BNode>(new BFb);
  ++count;
  for (int i = 0; i < branching; ++i) {
    auto c = baseline(depth - 1, !seq, branching, count);
    if (!seq) {
      auto w = std::make_unique<BForce>(0);
      ++count;
      w->kids.push_back(std::move(c));
      c = std::move(w);
    }
    n->kids.push_back(std::move(c));
  }
  if (!seq) {
    auto w = std::make_unique<BForce>(1);
    ++count;
    w->kids.push_back(std::move(n));
    return w;
  }
  return n;
}

void BM_Baseline_NaiveVirtualTree1000(benchmark::State& st) {
  int n = 0;
  auto root = baseline(8, true, 2, n);
  for (auto _ : st) benchmark::DoNotOptimize(root->tick());
  st.counters["nodes"] = n;
}
BENCHMARK(BM_Baseline_NaiveVirtualTree1000);

// ---- reactive tree with async actions: ReactiveSequence of 20 conditions guarding a running async action.
class NeverDone : public StatefulActionNode {
 public:
  using StatefulActionNode::StatefulActionNode;

 protected:
  NodeStatus onStart() override { return NodeStatus::RUNNING; }
  NodeStatus onRunning() override { return NodeStatus::RUNNING; }
  void onHalted() override {}
};

void BM_Tick_ReactiveAsync(benchmark::State& st) {
  NodeFactory f = factory();
  f.registerNodeType<NeverDone>("Work");
  std::string body = "<ReactiveSequence>";
  for (int i = 0; i < 20; ++i) body += "<Ok/>";
  body += "<Parallel success_count=\"-1\"><Work/><Work/><Work/></Parallel></ReactiveSequence>";
  ManualScheduler sched;  // outlives the tree
  Tree t = loadTreeFromText(f, "<root BTCPP_format=\"4\"><BehaviorTree ID=\"R\">" + body + "</BehaviorTree></root>");
  t.setScheduler(&sched);
  t.tickOnce();
  std::uint64_t a0 = g_allocs.load();
  for (auto _ : st) benchmark::DoNotOptimize(t.tickOnce());
  st.counters["allocs_per_tick"] = double(g_allocs.load() - a0) / double(st.iterations());
}
BENCHMARK(BM_Tick_ReactiveAsync);

// ---- blackboard reads
void BM_BlackboardRead_TypedSlot(benchmark::State& st) {
  auto bb = Blackboard::create();
  bb->set<int>("speed_limit", 42);
  PortInfo info = InputPort<int>("x");
  PortBinding b{&info, false, "", bb->getEntry("speed_limit"), nullptr};
  Input<int> in = Input<int>::fromBinding(b);
  int v = 0;
  for (auto _ : st) {
    in.get(v);
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_BlackboardRead_TypedSlot);

void BM_Baseline_BlackboardRead_StringMapAny(benchmark::State& st) {
  std::unordered_map<std::string, std::any> map;
  std::mutex m;
  for (int i = 0; i < 64; ++i) map["key_" + std::to_string(i)] = i;
  map["speed_limit"] = 42;
  const std::string key = "speed_limit";
  int v = 0;
  for (auto _ : st) {
    std::lock_guard lock(m);
    v = std::any_cast<int>(map.find(key)->second);
    benchmark::DoNotOptimize(v);
  }
}
BENCHMARK(BM_Baseline_BlackboardRead_StringMapAny);

void BM_Script_Evaluate(benchmark::State& st) {
  auto bb = Blackboard::create();
  bb->set<int>("battery", 80);
  Script s = Script::parse("battery > 20 && battery * 2 - 10 < 200");
  s.bind(*bb);
  bool r = false;
  std::uint64_t a0 = g_allocs.load();
  for (auto _ : st) {
    s.evaluateBool(r);
    benchmark::DoNotOptimize(r);
  }
  st.counters["allocs_per_eval"] = double(g_allocs.load() - a0) / double(st.iterations());
}
BENCHMARK(BM_Script_Evaluate);

}  // namespace

BENCHMARK_MAIN();
