#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <random>
#include <string>

#include "cairn/testing.hpp"

namespace cairn::testing {

std::string loopback_cyclone_config() {
  return "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><Peers><Peer address=\"127.0.0.1\"/></Peers><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>60</MaxAutoParticipantIndex></Discovery></Domain></CycloneDDS>";
}

int configure_isolated_dds() {
  if (!std::getenv("CAIRN_KEEP_CYCLONEDDS_URI")) setenv("CYCLONEDDS_URI", loopback_cyclone_config().c_str(), 1);
  // Always a fresh domain: an inherited CAIRN_DOMAIN_ID (a shell that sourced scripts/env.sh) would make
  // parallel test processes see each other. CAIRN_TEST_DOMAIN_ID forces one for debugging.
  if (const char* d = std::getenv("CAIRN_TEST_DOMAIN_ID")) {
    setenv("CAIRN_DOMAIN_ID", d, 1);
    return std::atoi(d);
  }
  std::random_device rd;
  std::mt19937 rng(rd() ^ static_cast<unsigned>(getpid()));
  const int domain = 1 + static_cast<int>(rng() % 230);
  setenv("CAIRN_DOMAIN_ID", std::to_string(domain).c_str(), 1);
  return domain;
}

}  // namespace cairn::testing

int main(int argc, char** argv) {
  cairn::testing::configure_isolated_dds();
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
