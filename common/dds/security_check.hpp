#pragma once
// Diagnosis of DDS Security files with OpenSSL (common/dds/security_check.cpp).
#include <string>

#include "common/dds/participant.hpp"

namespace teleop::dds {

/// Why Fast DDS's builtin security plugins would refuse these files, in one sentence naming the
/// file: a key that is not the certificate's, a certificate the identity CA does not verify
/// (another issuer, expired), governance or permissions the permissions CA did not sign, a
/// permissions subject that is not the certificate's, permissions outside their validity.
/// Empty when none of these is found. Called after the participant was refused, to explain it.
std::string diagnose_security_files(const SecurityFiles& files);

}  // namespace teleop::dds
