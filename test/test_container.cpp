// Components in a container: the zero-copy path between Talker and Listener, load/unload at run time
// over the DDS services, and a container that survives components that throw or hang.
#include <gtest/gtest.h>

#include <unistd.h>

#include <mutex>
#include <thread>

#include "cairn/container.hpp"
#include "cairn/demo/talker_listener.hpp"
#include "composition_interfaces/srv/ListNodes.hpp"
#include "composition_interfaces/srv/LoadNode.hpp"
#include "composition_interfaces/srv/UnloadNode.hpp"
#include "cairn/parameter_msgs.hpp"
#include "cairn/test_support.hpp"
#include "rcl_interfaces/srv/GetParameters.hpp"
#include "std_msgs/msg/String.hpp"

using namespace std::chrono_literals;
using namespace composition_interfaces::srv;

namespace {
/// A node in a context of its own, so its service calls cross DDS.
struct ClientNode {
  std::shared_ptr<cairn::Context> ctx = cairn::Context::create();
  cairn::Executor exec;
  std::unique_ptr<cairn::Node> node;
  ClientNode() {
    cairn::NodeOptions o("cli", &exec);
    o.context = ctx;
    o.start_parameter_services = false;
    node = std::make_unique<cairn::Node>(o);
  }
};
}  // namespace

TEST(Container, TalkerAndListenerInOneContainerShareTheMessageObject) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c1", loader);
  cairn::LoadRequest talker{"cairn_demo::Talker", "talker"};
  talker.parameters["rate_hz"] = 200.0;
  const auto t = mgr.load(talker);
  ASSERT_TRUE(t.ok) << t.error;
  const auto l = mgr.load(cairn::LoadRequest{"cairn_demo::Listener", "listener"});
  ASSERT_TRUE(l.ok) << l.error;
  auto* tk = static_cast<cairn_demo::Talker*>(mgr.get(t.unique_id).get());
  auto* ls = static_cast<cairn_demo::Listener*>(mgr.get(l.unique_id).get());
  exec.spin_until([&] { return ls->heard() >= 5; }, 10s);
  ASSERT_GE(ls->heard(), 5u);
  EXPECT_EQ(ls->heard_intra_process(), ls->heard()) << "in one container every message goes intra-process";
  // delivery is inline on the executor thread: the listener saw the very object the talker published
  EXPECT_EQ(ls->last_received_address(), tk->last_published_address());
  EXPECT_EQ(tk->published(), ls->heard());
}

TEST(Container, LoadListUnloadOverDdsServices) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec(cairn::Executor::Options{2});
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c2", loader);
  cairn::testing::Spinner spinner(exec);  // stops and joins on every way out (an ASSERT returning early too)

  ClientNode client;
  cairn::Node& cli = *client.node;
  auto load = cli.create_client<LoadNode_Request, LoadNode_Response>("/c2/_container/load_node");
  auto unload = cli.create_client<UnloadNode_Request, UnloadNode_Response>("/c2/_container/unload_node");
  auto list = cli.create_client<ListNodes_Request, ListNodes_Response>("/c2/_container/list_nodes");

  LoadNode_Request req;
  req.plugin_name = "cairn_demo::Talker";
  req.node_name = "t";
  req.node_namespace = "/robot";
  auto resp = load->call(req, 20s);
  ASSERT_TRUE(resp.has_value());
  ASSERT_TRUE(resp->success) << resp->error_message;
  EXPECT_EQ(resp->full_node_name, "/robot/t");

  req.plugin_name = "cairn_demo::NoSuchThing";
  auto bad = load->call(req, 20s);
  ASSERT_TRUE(bad.has_value());
  EXPECT_FALSE(bad->success);
  EXPECT_NE(bad->error_message.find("unknown component class 'cairn_demo::NoSuchThing'"), std::string::npos)
      << bad->error_message;

  req.plugin_name = "cairn_test::Throws";
  req.node_name = "thrower";
  auto thrown = load->call(req, 20s);
  ASSERT_TRUE(thrown.has_value());
  EXPECT_FALSE(thrown->success);
  EXPECT_NE(thrown->error_message.find("deliberate failure"), std::string::npos) << thrown->error_message;

  auto names = list->call(ListNodes_Request{}, 10s);
  ASSERT_TRUE(names.has_value());
  ASSERT_EQ(names->full_node_names.size(), 1u) << "failed loads must leave nothing behind";
  EXPECT_EQ(names->full_node_names[0], "/robot/t");

  UnloadNode_Request ureq;
  ureq.unique_id = names->unique_ids[0];
  auto u = unload->call(ureq, 10s);
  ASSERT_TRUE(u.has_value());
  EXPECT_TRUE(u->success) << u->error_message;
  ureq.unique_id = 999;
  auto u2 = unload->call(ureq, 10s);
  ASSERT_TRUE(u2.has_value());
  EXPECT_FALSE(u2->success);
  auto empty = list->call(ListNodes_Request{}, 10s);
  ASSERT_TRUE(empty.has_value());
  EXPECT_TRUE(empty->full_node_names.empty());
}

TEST(Container, LoadThatHangsTimesOutAndTheContainerKeepsServing) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c3", loader, cairn::ComponentManager::Options{300ms});
  cairn::LoadRequest hang{"cairn_test::Hangs", "sleepy"};
  hang.parameters["seconds"] = 2.0;
  const auto r = mgr.load(hang);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("did not finish constructing within 300 ms"), std::string::npos) << r.error;
  const auto ok = mgr.load(cairn::LoadRequest{"cairn_demo::Listener", "still_fine"});
  EXPECT_TRUE(ok.ok) << ok.error;
  EXPECT_EQ(mgr.list().size(), 1u);
}

TEST(Container, DuplicateNodeNamesAreRefused) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c4", loader);
  ASSERT_TRUE(mgr.load(cairn::LoadRequest{"cairn_demo::Listener", "same"}).ok);
  const auto r = mgr.load(cairn::LoadRequest{"cairn_demo::Listener", "same"});
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("already loaded"), std::string::npos) << r.error;
  // "robot" and "/robot/" are the namespace /robot: one name, and the second is a duplicate.
  cairn::LoadRequest a{"cairn_demo::Listener", "same"}, b = a, bad = a;
  a.node_namespace = "robot";
  b.node_namespace = "/robot/";
  bad.node_namespace = "9x";
  const auto ra = mgr.load(a);
  ASSERT_TRUE(ra.ok) << ra.error;
  EXPECT_EQ(ra.full_node_name, "/robot/same");
  const auto rb = mgr.load(b);
  EXPECT_FALSE(rb.ok);
  EXPECT_NE(rb.error.find("already loaded"), std::string::npos) << rb.error;
  const auto rbad = mgr.load(bad);
  EXPECT_FALSE(rbad.ok);
  EXPECT_NE(rbad.error.find("invalid namespace '9x'"), std::string::npos) << rbad.error;
}

// Like launch validation, a load with a parameter the component does not declare is refused (it used to load,
// the parameter silently ignored); the container keeps serving.
TEST(Container, UnknownParametersAreRefused) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec;
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c5", loader);
  cairn::LoadRequest bad{"cairn_demo::Talker", "t3"};
  bad.parameters["bogus"] = int64_t{1};
  const auto r = mgr.load(bad);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error.rfind("params.bogus: cairn_demo::Talker (/t3) has no such parameter (declared: ", 0), 0u) << r.error;
  EXPECT_TRUE(mgr.list().empty());
  cairn::LoadRequest good{"cairn_demo::Talker", "t3"};
  good.parameters["rate_hz"] = 5.0;
  const auto ok = mgr.load(good);
  EXPECT_TRUE(ok.ok) << ok.error;
  // A sender that validated the parameters itself (cairn launch: its spec validation constructs every component in
  // a dry run) spares the component that second construction; the container then takes its word for it.
  cairn::LoadRequest trusted{"cairn_demo::Talker", "t4"};
  trusted.parameters["bogus"] = int64_t{1};
  trusted.parameters_validated = true;
  const auto t = mgr.load(trusted);
  EXPECT_TRUE(t.ok) << t.error;
}

// A restart with restore_parameters brings a component back with what it was first loaded with (the bt executive's
// RestartComponent relies on it), over the load_node service; the container's `pid` parameter names its process.
TEST(Container, RestartRestoresTheOriginalLaunchParameters) {
  auto ctx = cairn::Context::create();
  cairn::Executor exec(cairn::Executor::Options{2});
  cairn::ComponentLoader loader;
  cairn::ComponentManager mgr(ctx, exec, "c5", loader);
  cairn::testing::Spinner spinner(exec);  // stops and joins on every way out (an ASSERT returning early too)

  cairn::LoadRequest first{"cairn_demo::Talker", "talker"};
  first.node_namespace = "/robot";
  first.parameters["rate_hz"] = 42.0;
  first.parameters["text"] = std::string("launched");
  first.remaps["/robot/chatter"] = "/speech";
  const auto a = mgr.load(first);
  ASSERT_TRUE(a.ok) << a.error;
  ASSERT_FALSE(mgr.unload(a.unique_id));

  ClientNode client;
  cairn::Node& cli = *client.node;
  auto load = cli.create_client<LoadNode_Request, LoadNode_Response>("/c5/_container/load_node");
  LoadNode_Request req;  // what a restart knows: class and name, not the parameters
  req.plugin_name = "cairn_demo::Talker";
  req.node_name = "talker";
  req.node_namespace = "/robot";
  rcl_interfaces::msg::Parameter restore;
  restore.name = "restore_parameters";
  restore.value = cairn::to_parameter_msg(cairn::ParameterValue(true));
  req.extra_arguments.push_back(restore);
  rcl_interfaces::msg::Parameter text;  // given parameters override the remembered ones
  text.name = "text";
  text.value = cairn::to_parameter_msg(cairn::ParameterValue(std::string("restarted")));
  req.parameters.push_back(text);
  auto resp = load->call(req, 20s);
  ASSERT_TRUE(resp.has_value());
  ASSERT_TRUE(resp->success) << resp->error_message;
  auto* t = static_cast<cairn::Node*>(static_cast<cairn_demo::Talker*>(mgr.get(resp->unique_id).get()));
  EXPECT_EQ(t->get_parameter<double>("rate_hz"), 42.0);
  EXPECT_EQ(t->get_parameter<std::string>("text"), "restarted");
  EXPECT_EQ(mgr.remembered("/robot/talker")->remaps.at("/robot/chatter"), "/speech");
  // ... and the restored node behaves so: it publishes on the remapped /speech with the overriding text (heard over
  // DDS from the client's context).
  std::mutex mu;
  std::string heard;
  auto speech = cli.create_subscription<std_msgs::msg::String>("/speech", cairn::QoS{}, [&](const std_msgs::msg::String& m) {
    std::lock_guard l(mu);
    heard = m.data;
  });
  EXPECT_TRUE(client.exec.spin_until([&] {
    std::lock_guard l(mu);
    return heard.rfind("restarted: ", 0) == 0;
  }, 20s)) << "heard on /speech: '" << heard << "'";

  req.node_name = "never_loaded";
  auto none = load->call(req, 20s);
  ASSERT_TRUE(none.has_value());
  EXPECT_FALSE(none->success);
  EXPECT_EQ(none->error_message, std::string(cairn::kNothingToRestore) + ": /robot/never_loaded was never loaded in container c5");
  cairn::LoadRequest other{"cairn_demo::Listener", "talker"};
  other.node_namespace = "/robot";
  other.restore_parameters = true;
  ASSERT_FALSE(mgr.unload(resp->unique_id));
  EXPECT_EQ(mgr.load(other).error, "cannot restore /robot/talker as cairn_demo::Listener: it was loaded as cairn_demo::Talker");

  auto params = cli.create_client<rcl_interfaces::srv::GetParameters_Request, rcl_interfaces::srv::GetParameters_Response>(
      "/c5/get_parameters");
  rcl_interfaces::srv::GetParameters_Request preq;
  preq.names = {"pid"};
  auto pid = params->call(preq, 20s);
  ASSERT_TRUE(pid.has_value());
  EXPECT_EQ(std::get<int64_t>(cairn::from_parameter_msg(pid->values.at(0))), static_cast<int64_t>(getpid()));
}
