#include "security/openssl_util.h"

#include <fcntl.h>
#include <openssl/asn1.h>
#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509v3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace auv::bringup {
namespace {

// OpenSSL's queued reasons, oldest first, so a message says why and not only what.
std::string opensslErrors() {
  std::string out;
  while (unsigned long code = ERR_get_error()) {
    char buffer[256];
    ERR_error_string_n(code, buffer, sizeof(buffer));
    out += out.empty() ? "" : "; ";
    out += buffer;
  }
  return out.empty() ? "no OpenSSL reason" : out;
}

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(what + " (" + opensslErrors() + ")");
}

struct BioDeleter {
  void operator()(BIO* bio) const { BIO_free_all(bio); }
};
using BioPtr = std::unique_ptr<BIO, BioDeleter>;

BioPtr openForWriting(const std::string& path, mode_t mode) {
  // open() with the final mode, so a private key is never readable by others, even briefly.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, mode);
  if (fd < 0) throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  ::fchmod(fd, mode);  // O_CREAT's mode is filtered by the umask; an existing file keeps its own
  FILE* file = ::fdopen(fd, "w");
  if (file == nullptr) {
    ::close(fd);
    throw std::runtime_error("cannot write " + path + ": " + std::strerror(errno));
  }
  return BioPtr(BIO_new_fp(file, BIO_CLOSE));
}

BioPtr openForReading(const std::string& path) {
  BioPtr bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) fail("cannot read " + path);
  return bio;
}

void addExtension(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value);
  if (ext == nullptr || !X509_add_ext(cert, ext, -1)) {
    X509_EXTENSION_free(ext);
    fail(std::string("cannot add certificate extension ") + value);
  }
  X509_EXTENSION_free(ext);
}

}  // namespace

PkeyPtr generateEcKey() {
  PkeyPtr key(EVP_EC_gen("prime256v1"));
  if (!key) fail("cannot generate a prime256v1 key");
  return key;
}

X509Ptr makeCertificate(const CertificateOptions& options, EVP_PKEY* key, X509* issuer,
                        EVP_PKEY* issuer_key) {
  X509Ptr cert(X509_new());
  if (!cert) fail("cannot allocate a certificate");
  X509_set_version(cert.get(), 2);  // v3, for the extensions
  ASN1_INTEGER_set(X509_get_serialNumber(cert.get()), options.serial);
  // Valid from an hour ago, so a peer whose clock is slightly behind accepts it.
  X509_gmtime_adj(X509_getm_notBefore(cert.get()), -3600);
  X509_gmtime_adj(X509_getm_notAfter(cert.get()), 86400L * options.valid_days);
  X509_NAME* name = X509_get_subject_name(cert.get());
  const auto add = [&](const char* field, const std::string& value) {
    if (!X509_NAME_add_entry_by_txt(name, field, MBSTRING_UTF8,
                                    reinterpret_cast<const unsigned char*>(value.c_str()), -1, -1,
                                    0))
      fail(std::string("cannot set certificate field ") + field + "=" + value);
  };
  add("O", options.organization);
  add("CN", options.common_name);
  X509* self_or_issuer = issuer != nullptr ? issuer : cert.get();
  X509_set_issuer_name(cert.get(), X509_get_subject_name(self_or_issuer));
  X509_set_pubkey(cert.get(), key);
  if (options.certificate_authority) {
    // digitalSignature too: the CA itself signs governance and permissions (S/MIME).
    addExtension(cert.get(), self_or_issuer, NID_basic_constraints, "critical,CA:TRUE");
    addExtension(cert.get(), self_or_issuer, NID_key_usage,
                 "critical,digitalSignature,keyCertSign,cRLSign");
  } else {
    addExtension(cert.get(), self_or_issuer, NID_basic_constraints, "CA:FALSE");
    addExtension(cert.get(), self_or_issuer, NID_key_usage, "critical,digitalSignature");
  }
  addExtension(cert.get(), self_or_issuer, NID_subject_key_identifier, "hash");
  if (!X509_sign(cert.get(), issuer_key != nullptr ? issuer_key : key, EVP_sha256()))
    fail("cannot sign the certificate of " + options.common_name);
  return cert;
}

std::string subjectName(X509* cert) {
  BioPtr bio(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(bio.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
  char* data = nullptr;
  const long size = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<size_t>(size));
}

uint64_t handshakeRank(const std::string& common_name, const std::string& organization) {
  // The same subject makeCertificate() writes: O then CN.
  std::unique_ptr<X509_NAME, decltype(&X509_NAME_free)> name(X509_NAME_new(), X509_NAME_free);
  X509_NAME_add_entry_by_txt(name.get(), "O", MBSTRING_UTF8,
                             reinterpret_cast<const unsigned char*>(organization.c_str()), -1, -1,
                             0);
  X509_NAME_add_entry_by_txt(name.get(), "CN", MBSTRING_UTF8,
                             reinterpret_cast<const unsigned char*>(common_name.c_str()), -1, -1,
                             0);
  const unsigned char* der = nullptr;
  size_t der_size = 0;
  if (!X509_NAME_get0_der(name.get(), &der, &der_size)) fail("cannot encode a subject name");
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int digest_size = 0;
  if (!EVP_Digest(der, der_size, digest, &digest_size, EVP_sha256(), nullptr))
    fail("cannot hash a subject name");
  uint64_t rank = 0x80 | (digest[0] >> 1);
  for (int i = 1; i < 6; ++i) rank = (rank << 8) | ((digest[i - 1] << 7 | digest[i] >> 1) & 0xff);
  return rank;
}

std::string notAfter(X509* cert) {
  struct tm time {};
  if (!ASN1_TIME_to_tm(X509_get0_notAfter(cert), &time)) fail("cannot read certificate expiry");
  char buffer[32];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%dT%H:%M:%SZ", &time);
  return buffer;
}

void writePrivateKey(const std::string& path, EVP_PKEY* key) {
  BioPtr bio = openForWriting(path, 0600);
  if (!PEM_write_bio_PrivateKey(bio.get(), key, nullptr, nullptr, 0, nullptr, nullptr))
    fail("cannot write " + path);
}

void writeCertificate(const std::string& path, X509* cert) {
  BioPtr bio = openForWriting(path, 0644);
  if (!PEM_write_bio_X509(bio.get(), cert)) fail("cannot write " + path);
}

PkeyPtr readPrivateKey(const std::string& path) {
  BioPtr bio = openForReading(path);
  PkeyPtr key(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
  if (!key) fail(path + " holds no PEM private key");
  return key;
}

X509Ptr readCertificate(const std::string& path) {
  BioPtr bio = openForReading(path);
  X509Ptr cert(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
  if (!cert) fail(path + " holds no PEM certificate");
  return cert;
}

void writeSignedDocument(const std::string& path, const std::string& document, X509* signer,
                         EVP_PKEY* signer_key) {
  // Streaming + detached: SMIME_write_PKCS7 writes the clear-text part and the signature
  // (the flow of OpenSSL's demos/smime/smsign.c).
  const int flags = PKCS7_DETACHED | PKCS7_STREAM | PKCS7_TEXT;
  BioPtr in(BIO_new_mem_buf(document.data(), static_cast<int>(document.size())));
  PKCS7* p7 = PKCS7_sign(signer, signer_key, nullptr, in.get(), flags);
  if (p7 == nullptr) fail("cannot sign " + path);
  BioPtr out = openForWriting(path, 0644);
  const bool ok = SMIME_write_PKCS7(out.get(), p7, in.get(), flags) == 1;
  PKCS7_free(p7);
  if (!ok) fail("cannot write " + path);
}

std::string verifySignedDocument(const std::string& path, X509* ca) {
  BioPtr in = openForReading(path);
  BIO* content = nullptr;
  PKCS7* p7 = SMIME_read_PKCS7(in.get(), &content);
  BioPtr content_owner(content);
  if (p7 == nullptr) fail(path + " is not an S/MIME signed document");
  X509_STORE* store = X509_STORE_new();
  X509_STORE_add_cert(store, ca);
  BioPtr out(BIO_new(BIO_s_mem()));
  const bool ok = PKCS7_verify(p7, nullptr, store, content, out.get(), PKCS7_TEXT) == 1;
  PKCS7_free(p7);
  X509_STORE_free(store);
  if (!ok) fail(path + ": signature does not verify against the keystore CA");
  char* data = nullptr;
  const long size = BIO_get_mem_data(out.get(), &data);
  return std::string(data, static_cast<size_t>(size));
}

}  // namespace auv::bringup
