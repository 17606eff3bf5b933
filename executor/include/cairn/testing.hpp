// Test support: Cyclone confined to loopback and a private, random domain id.
#ifndef CAIRN_TESTING_HPP
#define CAIRN_TESTING_HPP

#include <string>

namespace cairn::testing {

/// CYCLONEDDS_URI XML: loopback interface only, no multicast, unicast discovery on 127.0.0.1.
std::string loopback_cyclone_config();
/// Sets CYCLONEDDS_URI (unless CAIRN_KEEP_CYCLONEDDS_URI is set) and CAIRN_DOMAIN_ID to a random domain in
/// [1, 230] (or to $CAIRN_TEST_DOMAIN_ID), overriding an inherited CAIRN_DOMAIN_ID, so parallel test processes
/// never see each other. Returns the domain.
int configure_isolated_dds();

}  // namespace cairn::testing

#endif  // CAIRN_TESTING_HPP
