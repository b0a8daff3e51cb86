// Why DDS Security refused a participant's files, found with OpenSSL (the library Fast DDS's
// security plugins use). Fast DDS 2.9 only logs "[SECURITY Error] -> validate_local_identity"
// with no reason; this runs after it refused, to say which file and what is wrong.
#include "common/dds/security_check.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509_vfy.h>
#include <openssl/x509v3.h>

#include <ctime>
#include <memory>
#include <regex>

namespace teleop::dds {
namespace {

template <class T, void (*F)(T*)>
struct Deleter {
  void operator()(T* p) const {
    if (p) F(p);
  }
};
using BioPtr = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using X509Ptr = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using KeyPtr = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using StorePtr = std::unique_ptr<X509_STORE, Deleter<X509_STORE, X509_STORE_free>>;
using StoreCtxPtr = std::unique_ptr<X509_STORE_CTX, Deleter<X509_STORE_CTX, X509_STORE_CTX_free>>;
using Pkcs7Ptr = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

X509Ptr read_cert(const std::string& path) {
  BioPtr bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) return nullptr;
  return X509Ptr(PEM_read_bio_X509(bio.get(), nullptr, nullptr, nullptr));
}

KeyPtr read_key(const std::string& path) {
  BioPtr bio(BIO_new_file(path.c_str(), "r"));
  if (!bio) return nullptr;
  return KeyPtr(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
}

StorePtr store_of(X509* ca) {
  StorePtr store(X509_STORE_new());
  if (store && ca) X509_STORE_add_cert(store.get(), ca);
  // as permissive as a CA used only for this purpose should be: any key usage purpose
  if (store) X509_STORE_set_purpose(store.get(), X509_PURPOSE_ANY);
  return store;
}

std::string subject_rfc2253(X509* cert) {
  BioPtr bio(BIO_new(BIO_s_mem()));
  X509_NAME_print_ex(bio.get(), X509_get_subject_name(cert), 0, XN_FLAG_RFC2253);
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio.get(), &data);
  return std::string(data, static_cast<std::size_t>(n));
}

std::string no_spaces(std::string s) {
  std::erase(s, ' ');
  return s;
}

/// Verifies the S/MIME document at `path` with `ca` (read from `ca_path`); on success `content`
/// holds the signed text. Returns an empty string, or why it does not verify.
std::string verify_smime(const std::string& path, X509* ca, const std::string& ca_path,
                         std::string& content) {
  BioPtr in(BIO_new_file(path.c_str(), "r"));
  if (!in) return path + " cannot be read";
  BIO* raw_content = nullptr;
  Pkcs7Ptr p7(SMIME_read_PKCS7(in.get(), &raw_content));
  BioPtr signed_content(raw_content);
  if (!p7) return path + " is not an S/MIME signed document";
  StorePtr store = store_of(ca);
  BioPtr out(BIO_new(BIO_s_mem()));
  ERR_clear_error();
  if (PKCS7_verify(p7.get(), nullptr, store.get(), signed_content.get(), out.get(), PKCS7_TEXT) !=
      1) {
    char buf[256];
    ERR_error_string_n(ERR_get_error(), buf, sizeof(buf));
    return path + " does not verify with the permissions CA " + ca_path + " (" + buf + ")";
  }
  char* data = nullptr;
  const long n = BIO_get_mem_data(out.get(), &data);
  content.assign(data, static_cast<std::size_t>(n));
  return "";
}

std::string utc_now_iso() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%S", &tm);
  return buf;
}

std::string xml_field(const std::string& text, const std::string& tag) {
  const std::regex re("<" + tag + ">\\s*([^<]*?)\\s*</" + tag + ">");
  std::smatch m;
  return std::regex_search(text, m, re) ? m[1].str() : std::string();
}

}  // namespace

std::string diagnose_security_files(const SecurityFiles& f) {
  const X509Ptr identity_ca = read_cert(f.identity_ca);
  if (!identity_ca) return f.identity_ca + " is not a readable PEM certificate";
  const X509Ptr cert = read_cert(f.identity_certificate);
  if (!cert) return f.identity_certificate + " is not a readable PEM certificate";
  const KeyPtr key = read_key(f.private_key);
  if (!key) return f.private_key + " is not a readable (unencrypted) PEM private key";
  if (X509_check_private_key(cert.get(), key.get()) != 1) {
    return f.private_key + " is not the private key of " + f.identity_certificate;
  }
  {
    StorePtr store = store_of(identity_ca.get());
    StoreCtxPtr ctx(X509_STORE_CTX_new());
    X509_STORE_CTX_init(ctx.get(), store.get(), cert.get(), nullptr);
    if (X509_verify_cert(ctx.get()) != 1) {
      return f.identity_certificate + " does not verify with the identity CA " + f.identity_ca +
             ": " + X509_verify_cert_error_string(X509_STORE_CTX_get_error(ctx.get()));
    }
  }
  const X509Ptr permissions_ca = read_cert(f.permissions_ca);
  if (!permissions_ca) return f.permissions_ca + " is not a readable PEM certificate";
  std::string governance, permissions;
  if (auto why = verify_smime(f.governance, permissions_ca.get(), f.permissions_ca, governance);
      !why.empty()) {
    return why;
  }
  if (auto why = verify_smime(f.permissions, permissions_ca.get(), f.permissions_ca, permissions);
      !why.empty()) {
    return why;
  }
  const std::string subject = xml_field(permissions, "subject_name");
  const std::string cert_subject = subject_rfc2253(cert.get());
  if (no_spaces(subject) != no_spaces(cert_subject)) {
    return f.permissions + " grants subject '" + subject + "', but " + f.identity_certificate +
           " is '" + cert_subject + "'";
  }
  const std::string now = utc_now_iso(), not_before = xml_field(permissions, "not_before"),
                    not_after = xml_field(permissions, "not_after");
  if (!not_before.empty() && now < not_before) {
    return f.permissions + " is not valid before " + not_before + " (now " + now + " UTC)";
  }
  if (!not_after.empty() && now > not_after) {
    return f.permissions + " expired at " + not_after + " (now " + now + " UTC)";
  }
  return "";
}

}  // namespace teleop::dds
