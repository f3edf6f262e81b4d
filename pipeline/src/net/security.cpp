#include "netvmo/pipeline/net/security.hpp"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/pkcs7.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <algorithm>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <vector>

#include "dds_util.hpp"
#include "netvmo/pipeline/error.hpp"
#include "netvmo/pipeline/io/atomic_file.hpp"

namespace netvmo::net {
namespace fs = std::filesystem;

namespace {

template <class T, void (*F)(T*)>
struct Deleter {
  void operator()(T* p) const { F(p); }
};
using Key = std::unique_ptr<EVP_PKEY, Deleter<EVP_PKEY, EVP_PKEY_free>>;
using Cert = std::unique_ptr<X509, Deleter<X509, X509_free>>;
using Bio = std::unique_ptr<BIO, Deleter<BIO, BIO_free_all>>;
using Pkcs7 = std::unique_ptr<PKCS7, Deleter<PKCS7, PKCS7_free>>;

[[noreturn]] void ssl_fail(const std::string& what) {
  char buf[256] = "";
  ERR_error_string_n(ERR_get_error(), buf, sizeof buf);
  throw std::runtime_error("OpenSSL: " + what + ": " + buf);
}

template <class P>
P ok(P p, const std::string& what) {
  if (!p) ssl_fail(what);
  return p;
}

void ok(int rc, const std::string& what) {
  if (rc <= 0) ssl_fail(what);
}

Key ec_key() {
  return Key(ok(EVP_EC_gen("prime256v1"), "generate an EC key"));
}

void add_ext(X509* cert, X509* issuer, int nid, const char* value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, issuer, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = ok(X509V3_EXT_conf_nid(nullptr, &ctx, nid, value), "extension");
  ok(X509_add_ext(cert, ext, -1), "add extension");
  X509_EXTENSION_free(ext);
}

// A certificate for `key` with subject CN=cn, O=netvmo, signed by issuer (self-signed when
// issuer is null); a CA may sign certificates and documents.
Cert certificate(const std::string& cn, EVP_PKEY* key, X509* issuer, EVP_PKEY* issuer_key,
                 long serial, int days, bool ca) {
  Cert c(ok(X509_new(), "new certificate"));
  ok(X509_set_version(c.get(), 2), "version");
  ok(ASN1_INTEGER_set(X509_get_serialNumber(c.get()), serial), "serial");
  ok(X509_gmtime_adj(X509_getm_notBefore(c.get()), -3600) != nullptr, "not before");
  ok(X509_gmtime_adj(X509_getm_notAfter(c.get()), 86400L * days) != nullptr, "not after");
  ok(X509_set_pubkey(c.get(), key), "public key");
  X509_NAME* name = X509_get_subject_name(c.get());
  ok(X509_NAME_add_entry_by_txt(name, "O", MBSTRING_ASC,
                                reinterpret_cast<const unsigned char*>("netvmo"), -1, -1, 0),
     "subject");
  ok(X509_NAME_add_entry_by_txt(name, "CN", MBSTRING_ASC,
                                reinterpret_cast<const unsigned char*>(cn.c_str()), -1, -1, 0),
     "subject");
  X509* signer = issuer ? issuer : c.get();
  ok(X509_set_issuer_name(c.get(), X509_get_subject_name(signer)), "issuer");
  if (ca) {
    add_ext(c.get(), signer, NID_basic_constraints, "critical,CA:TRUE");
    // digitalSignature: the permissions CA signs the governance and permissions documents.
    add_ext(c.get(), signer, NID_key_usage, "critical,keyCertSign,cRLSign,digitalSignature");
  } else {
    add_ext(c.get(), signer, NID_basic_constraints, "critical,CA:FALSE");
    add_ext(c.get(), signer, NID_key_usage, "critical,digitalSignature,keyAgreement");
  }
  ok(X509_sign(c.get(), issuer_key ? issuer_key : key, EVP_sha256()), "sign certificate");
  return c;
}

Bio memory_bio() {
  return Bio(ok(BIO_new(BIO_s_mem()), "memory"));
}

// What was written into a memory BIO.
std::string text_of(BIO* b) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(b, &data);
  return std::string(data, static_cast<size_t>(n));
}

std::string pem(X509* cert) {
  const Bio b = memory_bio();
  ok(PEM_write_bio_X509(b.get(), cert), "write certificate");
  return text_of(b.get());
}

std::string pem(EVP_PKEY* key) {
  const Bio b = memory_bio();
  ok(PEM_write_bio_PrivateKey(b.get(), key, nullptr, nullptr, 0, nullptr, nullptr),
     "write private key");
  return text_of(b.get());
}

// `text` S/MIME-signed (clear text, detached signature), as `openssl smime -sign -text` writes.
std::string smime_signed(const std::string& text, X509* signer, EVP_PKEY* key) {
  Bio in(ok(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())), "memory"));
  const int flags = PKCS7_TEXT | PKCS7_DETACHED | PKCS7_STREAM;
  Pkcs7 p7(ok(PKCS7_sign(signer, key, nullptr, in.get(), flags), "sign document"));
  const Bio out = memory_bio();
  ok(SMIME_write_PKCS7(out.get(), p7.get(), in.get(), flags), "write signed document");
  return text_of(out.get());
}

std::string iso_time(std::time_t t) {
  char b[32];
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%S", &tm);
  return b;
}

const char* kDomains = "<domains><id_range><min>0</min><max>230</max></id_range></domains>";

std::string governance_xml() {
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )") +
         kDomains + R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string topics(const std::vector<std::string>& names) {
  std::string s = "<topics>";
  for (const auto& n : names) s += "<topic>" + n + "</topic>";
  return s + "</topics>";
}

std::string permissions_xml(const std::string& name, const std::vector<std::string>& publish,
                            const std::vector<std::string>& subscribe, std::time_t from,
                            std::time_t to) {
  std::string rule = std::string("<allow_rule>") + kDomains;
  if (!publish.empty()) rule += "<publish>" + topics(publish) + "</publish>";
  if (!subscribe.empty()) rule += "<subscribe>" + topics(subscribe) + "</subscribe>";
  rule += "</allow_rule>";
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         name + R"(">
      <subject_name>CN=)" +
         name + R"(,O=netvmo</subject_name>
      <validity><not_before>)" +
         iso_time(from) + "</not_before><not_after>" + iso_time(to) + R"(</not_after></validity>
      )" +
         rule +
         R"(
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

std::string file_uri(const fs::path& p) {
  return "file:" + fs::absolute(p).string();
}

}  // namespace

std::string camera_identity(int camera_id) {
  return "cam_" + std::to_string(camera_id);
}

SecurityIdentity security_identity(const fs::path& dir, const std::string& name) {
  SecurityIdentity id;
  id.name = name;
  id.identity_ca = dir / "identity_ca.pem";
  id.permissions_ca = dir / "permissions_ca.pem";
  id.governance = dir / "governance.p7s";
  id.certificate = dir / (name + ".cert.pem");
  id.private_key = dir / (name + ".key.pem");
  id.permissions = dir / (name + ".permissions.p7s");
  for (const auto* p : {&id.identity_ca, &id.permissions_ca, &id.governance, &id.certificate,
                        &id.private_key, &id.permissions})
    if (!fs::exists(*p))
      throw InputError(p->string() + ": not found (the security folder of " + name +
                       "; netvmo security init writes one)");
  return id;
}

void write_test_pki(const fs::path& dir, const io::NetworkConfig& net, int days) {
  if (days < 1) throw InputError("--days must be >= 1");
  fs::create_directories(dir);
  const std::time_t now = std::time(nullptr);
  const std::time_t from = now - 3600, to = now + 86400L * days;
  long serial = 1;
  const Key id_key = ec_key(), perm_key = ec_key();
  const Cert id_ca =
      certificate("netvmo identity CA", id_key.get(), nullptr, nullptr, serial++, days, true);
  const Cert perm_ca =
      certificate("netvmo permissions CA", perm_key.get(), nullptr, nullptr, serial++, days, true);
  const auto write = [&](const std::string& file, const std::string& text) {
    io::write_file_atomic(dir / file, text);
  };
  write("identity_ca.pem", pem(id_ca.get()));
  write("permissions_ca.pem", pem(perm_ca.get()));
  write("governance.p7s", smime_signed(governance_xml(), perm_ca.get(), perm_key.get()));

  const auto identity = [&](const std::string& name, const std::vector<std::string>& publish,
                            const std::vector<std::string>& subscribe) {
    const Key key = ec_key();
    const Cert cert =
        certificate(name, key.get(), id_ca.get(), id_key.get(), serial++, days, false);
    write(name + ".cert.pem", pem(cert.get()));
    write(name + ".key.pem", pem(key.get()));
    fs::permissions(dir / (name + ".key.pem"), fs::perms::owner_read | fs::perms::owner_write);
    write(name + ".permissions.p7s",
          smime_signed(permissions_xml(name, publish, subscribe, from, to), perm_ca.get(),
                       perm_key.get()));
  };
  std::vector<std::string> every_output, every_camera;
  for (const auto& c : net.cameras) {
    const std::string id = std::to_string(c.id);
    std::vector<std::string> sub;
    for (const auto& [a, b] : net.edges)
      if (a == c.id || b == c.id)
        sub.push_back("netvmo_estimates_" + std::to_string(a == c.id ? b : a));
    sub.push_back("rt/cam_" + id + "/*");  // its live camera topics
    identity(camera_identity(c.id),
             {"netvmo_estimates_" + id, "rt/netvmo/camera_" + id + "/*", "rt/tf", "rt/tf_static"},
             sub);
    every_output.push_back("rt/netvmo/camera_" + id + "/*");
    every_camera.push_back("rt/cam_" + id + "/*");
  }
  every_output.push_back("rt/tf");
  every_output.push_back("rt/tf_static");
  identity("viewer", {}, every_output);
  identity("player", every_camera, {});
}

dds_qos_t* security_qos(const SecurityIdentity& id) {
  dds_qos_t* q = dds_create_qos();
  const auto prop = [q](const char* name, const std::string& value) {
    dds_qset_prop(q, name, value.c_str());
  };
  prop("dds.sec.auth.library.path", "dds_security_auth");
  prop("dds.sec.auth.library.init", "init_authentication");
  prop("dds.sec.auth.library.finalize", "finalize_authentication");
  prop("dds.sec.crypto.library.path", "dds_security_crypto");
  prop("dds.sec.crypto.library.init", "init_crypto");
  prop("dds.sec.crypto.library.finalize", "finalize_crypto");
  prop("dds.sec.access.library.path", "dds_security_ac");
  prop("dds.sec.access.library.init", "init_access_control");
  prop("dds.sec.access.library.finalize", "finalize_access_control");
  prop("dds.sec.auth.identity_ca", file_uri(id.identity_ca));
  prop("dds.sec.auth.identity_certificate", file_uri(id.certificate));
  prop("dds.sec.auth.private_key", file_uri(id.private_key));
  prop("dds.sec.access.permissions_ca", file_uri(id.permissions_ca));
  prop("dds.sec.access.governance", file_uri(id.governance));
  prop("dds.sec.access.permissions", file_uri(id.permissions));
  return q;
}

dds_entity_t create_participant(int domain, const SecurityIdentity* id, const char* what) {
  dds_qos_t* q = id ? security_qos(*id) : nullptr;
  const dds_entity_t p = dds_create_participant(static_cast<dds_domainid_t>(domain), q, nullptr);
  if (q) dds_delete_qos(q);
  return detail::check(p, what);
}

}  // namespace netvmo::net
