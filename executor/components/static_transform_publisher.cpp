// cairn::StaticTransformPublisher: publishes the fixed joints of a URDF robot description as static
// transforms on /tf_static (latched), as robot_state_publisher does for fixed joints.
#include <urdf_parser/urdf_parser.h>

#include <fstream>
#include <sstream>

#include "cairn/component.hpp"
#include "cairn/tf.hpp"
#include "tf2_msgs/msg/TFMessage.hpp"

namespace cairn {

class StaticTransformPublisher : public Node {
 public:
  explicit StaticTransformPublisher(const NodeOptions& o) : Node(o) {
    const std::string file = declare_parameter<std::string>("urdf_file", "", {"URDF robot description to publish", {}, {}, true});
    const std::string prefix = declare_parameter<std::string>("frame_prefix", "", {"prepended to every frame name", {}, {}, true});
    if (file.empty()) throw std::invalid_argument("parameter 'urdf_file' is required");
    std::ifstream in(file);
    if (!in) throw std::invalid_argument("urdf_file: cannot read '" + file + "'");
    std::stringstream ss;
    ss << in.rdbuf();
    const auto model = urdf::parseURDF(ss.str());
    if (!model) throw std::invalid_argument("urdf_file: '" + file + "' is not a valid URDF (urdfdom rejected it)");
    tf2_msgs::msg::TFMessage msg;
    for (const auto& [name, joint] : model->joints_) {
      if (joint->type != urdf::Joint::FIXED) continue;
      geometry_msgs::msg::TransformStamped t;
      t.header.frame_id = prefix + joint->parent_link_name;
      t.child_frame_id = prefix + joint->child_link_name;
      const auto& p = joint->parent_to_joint_origin_transform;
      t.transform.translation.x = p.position.x;
      t.transform.translation.y = p.position.y;
      t.transform.translation.z = p.position.z;
      p.rotation.getQuaternion(t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                               t.transform.rotation.w);
      msg.transforms.push_back(t);
    }
    CAIRN_INFO(logger(), "robot '" << model->getName() << "': " << msg.transforms.size() << " fixed joints on /tf_static");
    pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", QoS::latched());
    if (!dry_run()) pub_->publish(std::move(msg));
  }

 private:
  std::shared_ptr<Publisher<tf2_msgs::msg::TFMessage>> pub_;
};

}  // namespace cairn

CAIRN_REGISTER_COMPONENT(cairn::StaticTransformPublisher)
