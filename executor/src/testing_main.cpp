#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
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
  const int domain = reserve_test_domain();
  setenv("CAIRN_DOMAIN_ID", std::to_string(domain).c_str(), 1);
  return domain;
}

int reserve_test_domain() {
  // A random domain alone let two of ctest's parallel processes draw the same one now and then (1 in 230 per
  // overlapping pair; two simulator tests then read each other's odometry and clock). Each process therefore
  // holds an exclusive lock on a file per domain for its lifetime, starting at a random domain and taking the
  // first one nobody holds.
  std::random_device rd;
  std::mt19937 rng(rd() ^ static_cast<unsigned>(getpid()));
  const int start = static_cast<int>(rng() % 230);
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
  for (int i = 0; i < 230 && !ec; ++i) {
    const int domain = 1 + (start + i) % 230;
    const std::string path = (dir / ("cairn_test_domain_" + std::to_string(domain) + ".lock")).string();
    const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) break;  // no writable temporary directory: fall back to the random domain
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;  // fd stays open: the lock lasts as long as the process
    close(fd);
  }
  return 1 + start;
}

}  // namespace cairn::testing

int main(int argc, char** argv) {
  cairn::testing::configure_isolated_dds();
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
