// Test support: Cyclone confined to loopback and a private, random domain id.
#ifndef CAIRN_TESTING_HPP
#define CAIRN_TESTING_HPP

#include <string>

namespace cairn::testing {

/// CYCLONEDDS_URI XML: loopback interface only, no multicast, unicast discovery on 127.0.0.1.
std::string loopback_cyclone_config();
/// Sets CYCLONEDDS_URI (unless CAIRN_KEEP_CYCLONEDDS_URI is set) and CAIRN_DOMAIN_ID to reserve_test_domain()
/// (or to $CAIRN_TEST_DOMAIN_ID), overriding an inherited CAIRN_DOMAIN_ID, so parallel test processes never see
/// each other. Returns the domain.
int configure_isolated_dds();
/// A domain in [1, 230] that no other process on this machine holds: starting at a random one, the first whose
/// lock file (<tmp>/cairn_test_domain_<id>.lock) this call can lock exclusively; the lock is held until the process
/// exits. Each call reserves another domain. Falls back to the random domain if no lock file can be created.
int reserve_test_domain();

}  // namespace cairn::testing

#endif  // CAIRN_TESTING_HPP
