// BehaviorTree.CPP v4 XML loading: several trees, include, TreeNodesModel, SubTree remapping, load-time errors
// with file:line.
#include <gtest/gtest.h>

#include "test_nodes.hpp"

using namespace cairn::bt;
using namespace cairn::bt::testing;

namespace {

const std::string kData = CAIRN_BT_TEST_DATA;

class Xml : public ::testing::Test {
 protected:
  void SetUp() override { g_journal = &journal; }
  void TearDown() override { g_journal = nullptr; }
  /// Loads `xml` and returns the LoadError (file:line: message) or "" on success.
  std::string loadError(const std::string& xml, const std::string& main = "") {
    try {
      LoadOptions o;
      o.main_tree = main;
      loadTreeFromText(factory, xml, o, "t.xml");
    } catch (const LoadError& e) {
      return e.what();
    }
    return "";
  }
  Journal journal;
  NodeFactory factory = makeFactory();
  ManualScheduler sched;
};

TEST_F(Xml, IncludeModelRemapAutoremapAndLiterals) {
  Tree t = loadTreeFromFile(factory, kData + "/main_with_include.xml");
  EXPECT_EQ(runUntilComplete(t, sched), NodeStatus::SUCCESS);
  auto bb = t.rootBlackboard();
  EXPECT_EQ(bb->get<int>("tries"), 2);  // typed through the SubTree model's inout_port
  EXPECT_EQ(bb->get<std::string>("target"), "kitchen");
  EXPECT_TRUE(bb->get<bool>("arrived"));
  EXPECT_EQ(bb->getEntry("_scratch"), nullptr);  // '_' keys are not auto-remapped
  EXPECT_EQ(bb->getEntry("goal"), nullptr);      // SubTree ports stay private unless remapped
  ASSERT_NE(t.findByPath("Sequence/approach/Sequence/SubTree/Script"), nullptr);
  EXPECT_EQ(listTreeIds(kData + "/main_with_include.xml"),
            (std::vector<std::string>{"Approach", "Report", "Mission"}));
}

TEST_F(Xml, SeveralTreesNeedAMainTree) {
  const std::string two = R"(<root BTCPP_format="4">
    <BehaviorTree ID="A"><AlwaysSuccess/></BehaviorTree>
    <BehaviorTree ID="B"><AlwaysFailure/></BehaviorTree></root>)";
  EXPECT_NE(loadError(two).find("main_tree_to_execute"), std::string::npos);
  LoadOptions o;
  o.main_tree = "B";
  EXPECT_EQ(loadTreeFromText(factory, two, o).tickOnce(), NodeStatus::FAILURE);
  EXPECT_EQ(loadError(two, "C"), "t.xml:1: no tree with ID 'C'");
}

TEST_F(Xml, LegacyIdFormAndSiblingNames) {
  Tree t = loadTreeFromText(factory, wrap(R"(<Sequence><Action ID="AlwaysSuccess"/><AlwaysSuccess/>
      <AlwaysSuccess name="x"/><Condition ID="ScriptCondition" code="true"/></Sequence>)"));
  TraceRecorder rec(t);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_TRUE(rec.has("1 Sequence/AlwaysSuccess#0 IDLE -> SUCCESS"));
  EXPECT_TRUE(rec.has("1 Sequence/AlwaysSuccess#1 IDLE -> SUCCESS"));
  EXPECT_TRUE(rec.has("1 Sequence/x IDLE -> SUCCESS"));
  EXPECT_TRUE(rec.has("1 Sequence/ScriptCondition IDLE -> SUCCESS"));
}

TEST_F(Xml, TypedPortsShareTypedSlots) {
  Tree t = loadTreeFromText(factory, wrap(R"(<Sequence><WriteInt out="{n}" value="41"/>
      <Script code="n += 1"/><ScriptCondition code="n == 42"/></Sequence>)"));
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  auto e = t.rootBlackboard()->getEntry("n");
  EXPECT_EQ(e->type().name, "int");
}

TEST_F(Xml, ErrorsCarryFileAndLine) {
  EXPECT_EQ(loadError("<root BTCPP_format=\"4\">\n<BehaviorTree ID=\"A\">\n  <Sequence>\n    <Fly/>\n"
                      "  </Sequence>\n</BehaviorTree></root>"),
            "t.xml:4: unknown node 'Fly'");
  EXPECT_EQ(loadError(wrap("<Sleep/>")), "t.xml:1: node 'Sleep' is missing required port 'msec'");
  EXPECT_EQ(loadError(wrap("<Sleep msec=\"1.5\"/>")),
            "t.xml:1: type mismatch in port 'msec' (int): cannot convert '1.5' to an integer");
  EXPECT_EQ(loadError(wrap("<Sleep msec=\"10\" speed=\"2\"/>")), "t.xml:1: node 'Sleep' has no port 'speed'");
  EXPECT_EQ(loadError(wrap("<Sleep msec=\"-5\"/>")), "t.xml:1: port 'msec' must not be negative, got -5");
  EXPECT_EQ(loadError(wrap("<Timeout msec=\"-1\"><AlwaysSuccess/></Timeout>")),
            "t.xml:1: port 'msec' must not be negative, got -1");
  EXPECT_EQ(loadError(wrap("<Delay delay_msec=\"-1\"><AlwaysSuccess/></Delay>")),
            "t.xml:1: port 'delay_msec' must not be negative, got -1");
  EXPECT_EQ(loadError(wrap("<Sleep msec=\"0\"/>")), "");
  EXPECT_EQ(loadError(wrap("<Parallel success_count=\"3\"><AlwaysSuccess/><AlwaysSuccess/></Parallel>")),
            "t.xml:1: Parallel thresholds success_count=3 failure_count=1 do not fit 2 children");
  EXPECT_EQ(loadError(wrap("<Parallel failure_count=\"-4\"><AlwaysSuccess/><AlwaysSuccess/></Parallel>")),
            "t.xml:1: Parallel thresholds success_count=-1 failure_count=-4 do not fit 2 children");
  EXPECT_EQ(loadError(wrap("<Parallel success_count=\"-2\"><AlwaysSuccess/><AlwaysSuccess/></Parallel>")), "");
  EXPECT_EQ(loadError(wrap("<Sequence>\n<WriteInt out=\"{k}\"/>\n<ReadString in=\"{k}\"/></Sequence>")),
            "t.xml:3: type mismatch: blackboard entry 'k' is int at t.xml:2 and std::string here");
  EXPECT_EQ(loadError(wrap("<ReadPose pose=\"1;2\"/>")),
            "t.xml:1: port 'pose' of type cairn::bt::testing::Pose2 needs a blackboard key, got '1;2'");
  EXPECT_EQ(loadError(wrap("<WriteInt out=\"n\"/>")),
            "t.xml:1: output port 'out' must be a blackboard key in braces, got 'n'");
  EXPECT_EQ(loadError(wrap("<Inverter/>")), "t.xml:1: node 'Inverter' has 0 children, expected 1");
  EXPECT_EQ(loadError(wrap("<IfThenElse><AlwaysSuccess/></IfThenElse>")),
            "t.xml:1: node 'IfThenElse' has 1 children, expected 2 to 3");
  EXPECT_EQ(loadError(wrap("<Script code=\"a := (1 +\"/>")),
            "t.xml:1: script in 'code', column 10: unexpected 'end of script'");
  EXPECT_EQ(loadError(wrap("<AlwaysSuccess _skipIf=\"x ==\"/>")),
            "t.xml:1: script in '_skipIf', column 5: unexpected 'end of script'");
  EXPECT_EQ(loadError(wrap("<Script code=\"undefined_key = 1\"/>")),
            "t.xml:1: script in 'code', column 1: blackboard entry 'undefined_key' does not exist (use ':=' to create it)");
  EXPECT_EQ(loadError("<root BTCPP_format=\"3\"/>"), "t.xml:1: unsupported BTCPP_format=\"3\" (only 4)");
  EXPECT_EQ(loadError("<root BTCPP_format=\"4\">\n<BehaviorTree ID=\"A\">\n<Sequence>\n</BehaviorTree></root>"),
            "t.xml:3: XML error: XML_ERROR_MISMATCHED_ELEMENT (XMLElement name=Sequence)");
  EXPECT_EQ(loadError(wrap("<SubTree ID=\"Nope\"/>")), "t.xml:1: unknown SubTree ID 'Nope'");
  EXPECT_EQ(loadError(wrap("<AlwaysSuccess/><AlwaysSuccess/>")),
            "t.xml:1: BehaviorTree 'Main' must have exactly one root node");
}

TEST_F(Xml, SubTreeCycleIsALoadError) {
  try {
    loadTreeFromFile(factory, kData + "/cycle.xml");
    FAIL();
  } catch (const LoadError& e) {
    EXPECT_EQ(e.line, 10);
    EXPECT_EQ(e.message, "SubTree cycle: A -> B -> A");
  }
}

TEST_F(Xml, MissingIncludeAndBadLiteralFromFiles) {
  try {
    loadTreeFromFile(factory, kData + "/missing_include.xml");
    FAIL();
  } catch (const LoadError& e) {
    EXPECT_EQ(e.line, 3);
    EXPECT_NE(e.message.find("included file not found"), std::string::npos);
  }
  try {
    loadTreeFromFile(factory, kData + "/bad_port.xml");
    FAIL();
  } catch (const LoadError& e) {
    EXPECT_EQ(e.file, kData + "/bad_port.xml");
    EXPECT_EQ(e.line, 4);
  }
}

TEST_F(Xml, PreconditionsOnSubTree) {
  const std::string xml = R"(<root BTCPP_format="4" main_tree_to_execute="M">
    <BehaviorTree ID="M"><Sequence><Script code="go := false"/>
      <SubTree ID="S" name="s" _skipIf="!go" _onSuccess="ran := true"/></Sequence></BehaviorTree>
    <BehaviorTree ID="S"><TestSync name="inner"/></BehaviorTree></root>)";
  Tree t = loadTreeFromText(factory, xml);
  EXPECT_EQ(t.tickOnce(), NodeStatus::SUCCESS);
  EXPECT_EQ(journal.count("inner.tick"), 0u);
  EXPECT_EQ(t.findByPath("Sequence/s")->kind(), NodeKind::SubTree);
}

TEST_F(Xml, SubTreeLiteralMustFitModelType) {
  const std::string xml = R"(<root BTCPP_format="4" main_tree_to_execute="M">
    <BehaviorTree ID="M"><SubTree ID="S" speed="fast"/></BehaviorTree>
    <BehaviorTree ID="S"><ScriptCondition code="speed > 0"/></BehaviorTree>
    <TreeNodesModel><SubTree ID="S"><input_port name="speed" type="double"/></SubTree></TreeNodesModel></root>)";
  EXPECT_EQ(loadError(xml),
            "t.xml:2: type mismatch in SubTree port 'speed': cannot convert 'fast' to a floating-point number");
}

TEST_F(Xml, TreeNodesModelRoundTrip) {
  std::string model = writeTreeNodesModel(factory);
  EXPECT_NE(model.find("<Action ID=\"TestAsync\">"), std::string::npos);
  EXPECT_EQ(model.find("ID=\"Sequence\""), std::string::npos);
  // A file with the exported model loads.
  std::string xml = model;
  xml.insert(xml.find("  <TreeNodesModel>"), "  <BehaviorTree ID=\"M\"><TestSync/></BehaviorTree>\n");
  EXPECT_EQ(loadError(xml), "");
}

}  // namespace
