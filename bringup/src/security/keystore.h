#pragma once
// A DDS Security keystore: a project CA, one identity (key + certificate + signed
// permissions) per process role, and the signed governance shared by all. Layout in
// docs/security.md; the backend finds the files with auv::interfaces::securityFiles().

#include <string>
#include <vector>

namespace auv::bringup {

struct KeystoreOptions {
  /// Identities to create, e.g. {"vehicle", "shore"}: letters, digits, '_' and '-'.
  std::vector<std::string> identities = {"vehicle", "shore"};
  /// The one DDS domain governance and permissions allow; -1 = every domain (0-230).
  int domain_id = -1;
  /// Validity of the CA, the certificates and the permissions [days].
  int valid_days = 3650;
  /// Organization (O=) of every subject name.
  std::string organization = "auv-inspect";
  /// Replace an existing keystore instead of refusing.
  bool force = false;
  /// Empty when valid, else what is wrong, naming the field.
  std::string check() const;
};

/// Creates the keystore in `folder`. Throws std::runtime_error when the folder already holds
/// a keystore (unless options.force), or on invalid options, naming the field.
void createKeystore(const std::string& folder, const KeystoreOptions& options);

/// Adds one identity to an existing keystore, signed by its CA (needs private/ca.key.pem).
void addIdentity(const std::string& folder, const std::string& identity,
                 const KeystoreOptions& options);

/// What `auv security list` shows of one identity.
struct IdentityInfo {
  std::string name;
  std::string subject;             ///< "CN=vehicle,O=auv-inspect"
  std::string certificate_expiry;  ///< "YYYY-MM-DDTHH:MM:SSZ"
  std::string problem;             ///< Empty when the files verify against the keystore CA.
};

/// The identities of the keystore in `folder`, each checked against the CA. Throws when
/// `folder` is not a keystore.
std::vector<IdentityInfo> listKeystore(const std::string& folder, std::string* ca_expiry);

/// Whether secured participants with `cyclonedds` identities can authenticate with ones
/// holding `fastdds` identities (Cyclone 0.10 cannot answer a Fast DDS 2.9 handshake request,
/// so every Cyclone identity must rank below every Fast DDS one; docs/security.md). Empty
/// when they can, else the diagnosis with names that would work.
std::string crossVendorProblem(const std::string& organization,
                               const std::vector<std::string>& cyclonedds,
                               const std::vector<std::string>& fastdds);
/// The organization recorded in the keystore in `folder`.
std::string keystoreOrganization(const std::string& folder);

/// The governance document (XML) of the keystore, exposed for tests.
std::string governanceXml(const KeystoreOptions& options);
/// The permissions document of one identity.
std::string permissionsXml(const std::string& identity, const std::string& subject,
                           const std::string& not_before, const std::string& not_after,
                           const KeystoreOptions& options);

}  // namespace auv::bringup
