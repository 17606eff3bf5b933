// The whole launch spec is validated before anything starts; each error names file:line and the key.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "cairn/launch.hpp"

namespace {
std::string error_of(const std::string& yaml) { return cairn::launch_spec_error(yaml, "spec.yaml"); }
}  // namespace

TEST(LaunchSpec, AValidSpecPasses) {
  EXPECT_EQ(error_of(R"(containers:
  - name: c
    threads: 2
    components:
      - class: cairn_demo::Talker
        params: {rate_hz: 5, text: hi}
      - class: cairn_demo::Listener
        namespace: /robot
        remap: {chatter: /chatter}
        isolated: true
processes:
  - name: p
    cmd: [echo, hi]
)"),
            "");
}

TEST(LaunchSpec, ParsesEverything) {
  auto spec = cairn::parse_launch_spec_text(R"(domain_id: 7
load_timeout: 3
containers:
  - name: c
    components:
      - class: cairn_demo::Talker
        name: t
        params: {rate_hz: 5.5}
        qos: {chatter: {reliability: best_effort, depth: 3}}
)",
                                            "x.yaml");
  ASSERT_EQ(spec.domain_id, 7);
  EXPECT_EQ(spec.load_timeout_s, 3.0);
  ASSERT_EQ(spec.containers.at(0).components.size(), 1u);
  const auto& c = spec.containers[0].components[0];
  EXPECT_EQ(c.fqn(), "/t");
  EXPECT_EQ(std::get<double>(c.params.at("rate_hz")), 5.5);
  EXPECT_EQ(c.qos.at("chatter").depth, 3);
  EXPECT_EQ(c.line, 6);
  // Namespaces are spelled as the node spells them ("robot/" is /robot); an invalid one names its line.
  auto ns = cairn::parse_launch_spec_text("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                                          "        namespace: robot/\n",
                                          "x.yaml");
  EXPECT_EQ(ns.containers.at(0).components.at(0).fqn(), "/robot/talker");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "        namespace: 9x\n"),
            "spec.yaml:5: component.namespace: invalid namespace '9x'");
}

TEST(LaunchSpec, YamlSyntaxErrorNamesTheLine) {
  EXPECT_EQ(error_of("containers:\n  - name: [unclosed\n").substr(0, 12), "spec.yaml:3:");
}

TEST(LaunchSpec, UnknownKey) {
  EXPECT_EQ(error_of("containers:\n  - name: c\n    component: []\n"),
            "spec.yaml:3: container: unknown key 'component' (allowed: name, threads, components, respawn, respawn_delay)");
}

TEST(LaunchSpec, UnknownComponentClass) {
  const auto e = error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talkr\n");
  EXPECT_EQ(e.rfind("spec.yaml:4: component.class: unknown component class 'cairn_demo::Talkr' (known: ", 0), 0u) << e;
}

TEST(LaunchSpec, ParameterOfTheWrongType) {
  const auto e = error_of(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params:\n"
      "          rate_hz: fast\n");
  EXPECT_EQ(e, "spec.yaml:6: params: /talker: parameter 'rate_hz' expects double, got string (\"fast\")");
}

TEST(LaunchSpec, ParameterOutOfRange) {
  const auto e = error_of(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params: {rate_hz: -1}\n");
  EXPECT_EQ(e, "spec.yaml:5: params: /talker: parameter 'rate_hz' = -1 is outside [0.001, 10000]");
}

TEST(LaunchSpec, UnknownParameter) {
  const auto e = error_of(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params: {rate: 3}\n");
  EXPECT_NE(e.find("spec.yaml:5: params.rate: cairn_demo::Talker (/talker) has no such parameter (declared: "),
            std::string::npos)
      << e;
}

TEST(LaunchSpec, DuplicateNames) {
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "      - class: cairn_demo::Talker\n"),
            "spec.yaml:5: component: duplicate node name '/talker'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n  - name: c\n"), "spec.yaml:3: container.name: duplicate name 'c'");
  // A container is a node too: a component of the same name would be a second /talker.
  EXPECT_EQ(error_of("containers:\n  - name: talker\n    components:\n      - class: cairn_demo::Talker\n"),
            "spec.yaml:4: component: node name '/talker' is also container talker's node name");
  // An isolated component runs in container <container>__<name>, which must not be a declared container.
  EXPECT_EQ(error_of("containers:\n  - name: a__b\n  - name: a\n    components:\n"
                     "      - class: cairn_demo::Talker\n        name: b\n        isolated: true\n"),
            "spec.yaml:5: component: isolated, it runs in container 'a__b', a name that is already taken");
}

// A repeated key used to be accepted with the second entry silently ignored (yaml-cpp finds only the first).
TEST(LaunchSpec, RepeatedKeys) {
  EXPECT_EQ(error_of("containers:\n  - name: a\ncontainers:\n  - name: b\n"), "spec.yaml:3: spec: duplicate key 'containers'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "        params: {rate_hz: 1.0, rate_hz: 2.0}\n"),
            "spec.yaml:5: component.params: duplicate key 'rate_hz'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    threads: 2\n    threads: 3\n"),
            "spec.yaml:4: container: duplicate key 'threads'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "        qos: {chatter: {depth: 5, depth: 7}}\n"),
            "spec.yaml:5: qos.chatter: duplicate key 'depth'");
}

TEST(LaunchSpec, RemappingThatJoinsTwoMessageTypes) {
  const auto e = error_of(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Listener\n"
      "      - class: cairn_test::ImagePublisher\n        remap: {chatter: /chatter}\n");
  EXPECT_NE(e.find("spec.yaml:6: topic /chatter: /image_publisher uses sensor_msgs/msg/Image but /listener uses "
                   "std_msgs/msg/String"),
            std::string::npos)
      << e;
}

TEST(LaunchSpec, QosThatNeverMatches) {
  const auto e = error_of(
      "containers:\n  - name: c\n    components:\n      - class: cairn_test::BestEffortTalker\n"
      "      - class: cairn_demo::Listener\n");
  EXPECT_NE(e.find("spec.yaml:5: topic /chatter: /listener never hears /best_effort_talker: subscription requests "
                   "reliable delivery"),
            std::string::npos)
      << e;
}

TEST(LaunchSpec, BadValuesOfKnownKeys) {
  EXPECT_EQ(error_of("containers:\n  - name: c\n    threads: many\n"),
            "spec.yaml:3: container.threads: expected an integer, got 'many'");
  // NaN compared false against the range and was taken (threads = a NaN cast to size_t); trailing garbage too
  EXPECT_EQ(error_of("containers:\n  - name: c\n    threads: nan\n"),
            "spec.yaml:3: container.threads: expected an integer, got 'nan'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    threads: 2 3\n"),
            "spec.yaml:3: container.threads: expected an integer, got '2 3'");
  // 2.5 threads and domain 7.5 were truncated silently
  EXPECT_EQ(error_of("containers:\n  - name: c\n    threads: 2.5\n"),
            "spec.yaml:3: container.threads: expected an integer, got '2.5'");
  EXPECT_EQ(error_of("domain_id: 7.5\ncontainers:\n  - name: c\n"), "spec.yaml:1: domain_id: expected an integer, got '7.5'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "        qos: {chatter: {reliability: sometimes}}\n"),
            "spec.yaml:5: qos.chatter: qos reliability expects reliable or best_effort, got 'sometimes'");
  // "inf" and 1e300 s were converted to int64 nanoseconds (undefined behaviour); "+-1" was read as -1
  for (const char* bad : {"inf", "1e300", "+-1"})
    EXPECT_EQ(error_of(std::string("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                                   "        qos: {chatter: {deadline: '") + bad + "'}}\n"),
              std::string("spec.yaml:5: qos.chatter: qos deadline expects seconds in [0, 9e9], got '") + bad + "'");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                     "        qos: {chatter: {depth: 99999999999}}\n"),
            "spec.yaml:5: qos.chatter: qos depth expects an integer >= 1, got '99999999999'");
  EXPECT_EQ(error_of("processes:\n  - name: p\n"), "spec.yaml:2: process.cmd: expected a non-empty list");
  EXPECT_EQ(error_of("[1, 2]\n"), "spec.yaml:1: a launch spec is a map with 'containers' and/or 'processes'");
  EXPECT_EQ(error_of("containers:\n  - name: 9lives\n"), "spec.yaml:2: container.name: '9lives' is not a valid node name");
}

TEST(LaunchSpec, RespawnOptionsAndTheirBackoff) {
  auto spec = cairn::parse_launch_spec_text("containers:\n  - name: c\n    respawn_delay: 0.5\n  - name: d\n    respawn: false\n"
                                            "processes:\n  - name: p\n    cmd: [sleep, '1']\n    respawn: true\n",
                                            "x.yaml");
  const auto& c = spec.containers.at(0).respawn;
  EXPECT_TRUE(c.respawn);
  EXPECT_EQ(c.delay_for(1), 0.5);
  EXPECT_EQ(c.delay_for(2), 1.0);
  EXPECT_EQ(c.delay_for(4), 4.0);
  EXPECT_EQ(c.delay_for(20), 30.0);  // capped
  EXPECT_FALSE(spec.containers.at(1).respawn.respawn);
  EXPECT_TRUE(spec.processes.at(0).respawn.respawn);
  EXPECT_EQ(spec.processes.at(0).respawn.delay_for(1), 0.1);  // default
  EXPECT_EQ((cairn::RespawnPolicy{true, 60.0}.delay_for(3)), 60.0);  // a delay above the cap stays
  EXPECT_EQ(error_of("containers:\n  - name: c\n    respawn_delay: -1\n"),
            "spec.yaml:3: container.respawn_delay: -1 is outside [0, 3600]");
  EXPECT_EQ(error_of("containers:\n  - name: c\n    respawn: often\n"), "spec.yaml:3: container.respawn: expected true or false");
  EXPECT_EQ(error_of("processes:\n  - name: p\n    cmd: [x]\n    respawn_delay: soon\n"),
            "spec.yaml:4: process.respawn_delay: expected a number, got 'soon'");
}

TEST(LaunchSpec, ComponentThatThrowsInItsConstructor) {
  const auto e = error_of("containers:\n  - name: c\n    components:\n      - class: cairn_test::Throws\n");
  EXPECT_EQ(e, "spec.yaml:4: cairn_test::Throws (/throws) cannot be constructed: deliberate failure");
}

TEST(LaunchSpec, ParameterFiles) {
  const std::string dir = "/tmp/cairn_params_" + std::to_string(::getpid());
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir + "/good.yaml") << "/talker:\n  ros__parameters:\n    rate_hz: 3.5\n    text: from file\n";
    std::ofstream(dir + "/bad.yaml") << "/talker:\n  ros__parameters:\n    rate_hz: [1, {x: 2}]\n";
    std::ofstream(dir + "/broken.yaml") << "/talker: [\n";
    std::ofstream(dir + "/flat.yaml") << "rate_hz: abc\n";
    std::ofstream(dir + "/other.yaml") << "/other:\n  ros__parameters:\n    rate_hz: 1.0\n";
    std::ofstream(dir + "/shared.yaml") << "/other:\n  ros__parameters: {x: 1}\n/**:\n  ros__parameters: {text: all}\n";
  }
  cairn::ComponentLoader loader;
  auto spec = cairn::parse_launch_spec_text(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params: {text: inline}\n"
      "        params_file: good.yaml\n",
      dir + "/spec.yaml");
  const auto& p = spec.containers[0].components[0].params;
  EXPECT_EQ(std::get<double>(p.at("rate_hz")), 3.5);
  EXPECT_EQ(std::get<std::string>(p.at("text")), "inline") << "inline params win over the file";
  EXPECT_NO_THROW(cairn::validate_launch_spec(spec, loader));
  auto err = [&](const std::string& file) -> std::string {
    try {
      cairn::parse_launch_spec_text("containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n"
                                    "        params_file: " + file + "\n", dir + "/spec.yaml");
    } catch (const cairn::LaunchError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(err("bad.yaml"), dir + "/bad.yaml:3: /talker.ros__parameters.rate_hz: parameter arrays hold scalars only");
  EXPECT_EQ(err("broken.yaml").rfind(dir + "/broken.yaml:", 0), 0u) << err("broken.yaml");
  EXPECT_EQ(err("missing.yaml"), dir + "/spec.yaml:5: component.params_file: cannot read '" + dir + "/missing.yaml'");
  // a directory is an unreadable file, not a raw stream exception
  EXPECT_EQ(err(dir), dir + "/spec.yaml:5: component.params_file: cannot read '" + dir + "' (a directory)");
  // a file that holds nothing for the component would silently not apply
  EXPECT_EQ(err("flat.yaml"), dir + "/spec.yaml:5: component.params_file: '" + dir +
                                  "/flat.yaml' has no entry for /talker (its keys: rate_hz; expected /talker, talker or "
                                  "/** mapping to {ros__parameters: {...}})");
  EXPECT_NE(err("other.yaml").find("other.yaml' has no entry for /talker (its keys: /other;"), std::string::npos)
      << err("other.yaml");
  EXPECT_EQ(err("shared.yaml"), "") << "/** applies to every node";
  // A repeated key in the file: the second value was silently ignored.
  std::ofstream(dir + "/twice.yaml") << "/talker:\n  ros__parameters:\n    rate_hz: 1.0\n    rate_hz: 2.0\n";
  EXPECT_EQ(err("twice.yaml"), dir + "/twice.yaml:4: /talker.ros__parameters: duplicate key 'rate_hz'");
  // A parameter the component does not declare, from the file, is refused like an inline one.
  std::ofstream(dir + "/unknown.yaml") << "/talker:\n  ros__parameters:\n    bogus: 1\n";
  auto with_unknown = cairn::parse_launch_spec_text(
      "containers:\n  - name: c\n    components:\n      - class: cairn_demo::Talker\n        params_file: unknown.yaml\n",
      dir + "/spec.yaml");
  EXPECT_THROW(cairn::validate_launch_spec(with_unknown, loader), cairn::LaunchError);
}
