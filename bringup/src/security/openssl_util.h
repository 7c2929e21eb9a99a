#pragma once
// The few OpenSSL (libcrypto) operations a DDS Security keystore needs: prime256v1 keys,
// X.509 certificates signed by a CA, and S/MIME signatures of the governance and permissions
// documents. Every failure throws std::runtime_error with OpenSSL's reason and the file.

#include <openssl/evp.h>
#include <openssl/x509.h>

#include <cstdint>
#include <memory>
#include <string>

namespace auv::bringup {

struct PkeyDeleter {
  void operator()(EVP_PKEY* key) const { EVP_PKEY_free(key); }
};
struct X509Deleter {
  void operator()(X509* cert) const { X509_free(cert); }
};
using PkeyPtr = std::unique_ptr<EVP_PKEY, PkeyDeleter>;
using X509Ptr = std::unique_ptr<X509, X509Deleter>;

/// A new ECDSA key on the prime256v1 (P-256) curve, the curve both DDS vendors accept.
PkeyPtr generateEcKey();

/// What goes into a certificate besides its key.
struct CertificateOptions {
  std::string common_name;             ///< CN of the subject.
  std::string organization;            ///< O of the subject.
  int valid_days = 3650;               ///< From now.
  bool certificate_authority = false;  ///< CA:TRUE with keyCertSign, else an end entity.
  long serial = 1;                     ///< Unique per issuing CA.
};

/// A certificate for `key`, signed with SHA-256 by `issuer_key` (self-signed when
/// `issuer` is null).
X509Ptr makeCertificate(const CertificateOptions& options, EVP_PKEY* key, X509* issuer,
                        EVP_PKEY* issuer_key);

/// The subject as DDS Security permissions write it: "CN=vehicle,O=auv-inspect" (RFC 2253,
/// most specific first; see docs/security.md on the order).
std::string subjectName(X509* cert);
/// The 48 bits DDS Security puts first in a secured participant's GUID prefix: '1' and 47
/// bits of SHA-256 of the DER subject name (spec 9.3.3). They decide which of two peers
/// starts the authentication handshake: the lower one (checked on both vendors).
uint64_t handshakeRank(const std::string& common_name, const std::string& organization);

/// Expiry of `cert` as "YYYY-MM-DDTHH:MM:SSZ".
std::string notAfter(X509* cert);

/// Writes PEM files; private keys are created with mode 0600 before any byte is written.
void writePrivateKey(const std::string& path, EVP_PKEY* key);
void writeCertificate(const std::string& path, X509* cert);
PkeyPtr readPrivateKey(const std::string& path);
X509Ptr readCertificate(const std::string& path);

/// Signs `document` with the CA (detached S/MIME, text mode, as `openssl smime -sign -text`
/// does and both vendors verify) and writes it to `path`.
void writeSignedDocument(const std::string& path, const std::string& document, X509* signer,
                         EVP_PKEY* signer_key);
/// Checks the S/MIME file `path` against `ca`; returns the signed document or throws.
std::string verifySignedDocument(const std::string& path, X509* ca);

}  // namespace auv::bringup
