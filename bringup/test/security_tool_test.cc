// `auv security` and the keystore it writes: layout, modes, signatures, refusing to
// overwrite, bad arguments, and how the backend resolves an identity's files. No DDS traffic.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "auv/interfaces/backend.h"
#include "security/keystore.h"
#include "security/openssl_util.h"

namespace auv::bringup {
namespace {

namespace fs = std::filesystem;

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

unsigned mode(const fs::path& path) {
  struct stat st {};
  EXPECT_EQ(::stat(path.c_str(), &st), 0) << path;
  return st.st_mode & 0777;
}

// Output (stdout + stderr) and exit code of `auv-security <args>`.
struct ToolRun {
  int code = -1;
  std::string output;
};
ToolRun runTool(const std::string& args) {
  ToolRun run;
  const std::string command = std::string(AUV_SECURITY_EXECUTABLE) + " " + args + " 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  char buffer[512];
  while (pipe != nullptr && std::fgets(buffer, sizeof(buffer), pipe) != nullptr)
    run.output += buffer;
  const int status = pipe != nullptr ? ::pclose(pipe) : -1;
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

class KeystoreTest : public testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/auv-security-test-XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(KeystoreTest, InitWritesTheDocumentedLayout) {
  const fs::path ks = dir_ / "keys";
  const ToolRun run =
      runTool("init " + ks.string() + " --identities vehicle,shore,probe --domain 7");
  ASSERT_EQ(run.code, 0) << run.output;
  for (const char* file :
       {"ca.cert.pem", "private/ca.key.pem", "governance.xml", "governance.p7s", "keystore.yaml"})
    EXPECT_TRUE(fs::is_regular_file(ks / file)) << file;
  EXPECT_EQ(mode(ks / "private/ca.key.pem"), 0600u);
  EXPECT_EQ(mode(ks / "private"), 0700u);
  for (const std::string name : {"vehicle", "shore", "probe"}) {
    const interfaces::SecurityFiles files = interfaces::securityFiles(ks.string(), name);
    for (const std::string& file : {files.certificate, files.private_key, files.permissions,
                                    files.identity_ca, files.governance})
      EXPECT_TRUE(fs::is_regular_file(file)) << file;
    EXPECT_EQ(mode(files.private_key), 0600u) << name;
    X509Ptr cert = readCertificate(files.certificate);
    EXPECT_EQ(subjectName(cert.get()), "CN=" + name + ",O=auv-inspect");
    // The permissions name the certificate's subject and the one domain, signed by the CA.
    X509Ptr ca = readCertificate(files.identity_ca);
    const std::string permissions = verifySignedDocument(files.permissions, ca.get());
    EXPECT_NE(permissions.find("<subject_name>CN=" + name + ",O=auv-inspect</subject_name>"),
              std::string::npos);
    EXPECT_NE(permissions.find("<id>7</id>"), std::string::npos);
    // S/MIME text mode signs the canonical form (CRLF line ends); the .xml copy has LF.
    std::string lf = permissions;
    lf.erase(std::remove(lf.begin(), lf.end(), '\r'), lf.end());
    EXPECT_EQ(lf, readFile(fs::path(files.permissions).replace_extension(".xml")));
  }
  X509Ptr ca = readCertificate(ks / "ca.cert.pem");
  const std::string governance = verifySignedDocument((ks / "governance.p7s").string(), ca.get());
  EXPECT_NE(governance.find("<data_protection_kind>ENCRYPT</data_protection_kind>"),
            std::string::npos);
  EXPECT_NE(governance.find("<discovery_protection_kind>ENCRYPT</discovery_protection_kind>"),
            std::string::npos);
  EXPECT_NE(governance.find("<allow_unauthenticated_participants>false"), std::string::npos);

  const ToolRun list = runTool("list " + ks.string());
  EXPECT_EQ(list.code, 0) << list.output;
  for (const char* name : {"vehicle\tCN=vehicle,O=auv-inspect", "shore\t", "probe\t"})
    EXPECT_NE(list.output.find(name), std::string::npos) << list.output;
  EXPECT_EQ(list.output.find("INVALID"), std::string::npos) << list.output;
}

TEST_F(KeystoreTest, RefusesToOverwriteUnlessForced) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string()).code, 0);
  const std::string ca = readFile(ks / "ca.cert.pem");
  const ToolRun again = runTool("init " + ks.string() + " --identities other");
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.output.find("refusing to overwrite"), std::string::npos) << again.output;
  EXPECT_EQ(readFile(ks / "ca.cert.pem"), ca) << "the old keystore must be untouched";
  EXPECT_TRUE(fs::exists(ks / "identities/vehicle/key.pem"));

  const ToolRun forced = runTool("init " + ks.string() + " --identities other --force");
  ASSERT_EQ(forced.code, 0) << forced.output;
  EXPECT_NE(readFile(ks / "ca.cert.pem"), ca);
  EXPECT_TRUE(fs::exists(ks / "identities/other/key.pem"));
  EXPECT_FALSE(fs::exists(ks / "identities/vehicle")) << "a forced init replaces, not merges";
  for (const auto& entry : fs::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename(), "keys") << "no staging folder left behind";
}

TEST_F(KeystoreTest, RefusesAFolderThatIsNotAKeystore) {
  const fs::path folder = dir_ / "documents";
  fs::create_directories(folder);
  std::ofstream(folder / "thesis.txt") << "precious";
  const ToolRun run = runTool("init " + folder.string() + " --force");
  EXPECT_EQ(run.code, 1);
  EXPECT_NE(run.output.find("not a keystore"), std::string::npos) << run.output;
  EXPECT_EQ(readFile(folder / "thesis.txt"), "precious");
}

TEST_F(KeystoreTest, BadArgumentsNameTheOption) {
  const std::string ks = (dir_ / "keys").string();
  const struct {
    std::string args;
    std::string message;
  } cases[] = {
      {"init " + ks + " --domain 300", "--domain"},
      {"init " + ks + " --domain seven", "--domain: expected an integer"},
      {"init " + ks + " --identities vehicle,", "identities: '' is not a valid identity"},
      {"init " + ks + " --identities ../etc", "'../etc' is not a valid identity"},
      {"init " + ks + " --identities a,a", "'a' is given twice"},
      {"init " + ks + " --days 0", "--days"},
      {"init " + ks + " --organization A,B", "organization"},
      {"init " + ks + " --colour blue", "unknown option --colour"},
      {"init " + ks + " --days", "--days: needs a value"},
      {"init", "give exactly one keystore folder"},
      {"frobnicate " + ks, "unknown command 'frobnicate'"},
  };
  for (const auto& c : cases) {
    const ToolRun run = runTool(c.args);
    EXPECT_EQ(run.code, 2) << c.args << "\n" << run.output;
    EXPECT_NE(run.output.find(c.message), std::string::npos) << c.args << "\n" << run.output;
    EXPECT_FALSE(fs::exists(ks)) << c.args << " must not write anything";
  }
  const ToolRun list = runTool("list " + ks);
  EXPECT_EQ(list.code, 1);
  EXPECT_NE(list.output.find("is not a keystore"), std::string::npos) << list.output;
}

TEST_F(KeystoreTest, ListReportsATamperedPermissionsDocument) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string()).code, 0);
  const fs::path permissions = ks / "identities/shore/permissions.p7s";
  std::string text = readFile(permissions);
  const size_t deny = text.find("<default>DENY</default>");
  ASSERT_NE(deny, std::string::npos);
  text.replace(deny, 23, "<default>ALLOW</default>");
  std::ofstream(permissions) << text;
  const ToolRun list = runTool("list " + ks.string());
  EXPECT_EQ(list.code, 1);
  EXPECT_NE(list.output.find("shore\tCN=shore,O=auv-inspect"), std::string::npos);
  EXPECT_NE(list.output.find("INVALID: " + permissions.string()), std::string::npos) << list.output;
  EXPECT_NE(list.output.find("vehicle\tCN=vehicle,O=auv-inspect\texpires"), std::string::npos);
}

TEST_F(KeystoreTest, AddSignsANewIdentityWithTheSameCa) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string() + " --domain 3").code, 0);
  const ToolRun add = runTool("add " + ks.string() + " camera_1");
  ASSERT_EQ(add.code, 0) << add.output;
  const ToolRun twice = runTool("add " + ks.string() + " camera_1");
  EXPECT_EQ(twice.code, 1);
  EXPECT_NE(twice.output.find("already exists"), std::string::npos) << twice.output;
  X509Ptr ca = readCertificate(ks / "ca.cert.pem");
  const std::string permissions =
      verifySignedDocument((ks / "identities/camera_1/permissions.p7s").string(), ca.get());
  EXPECT_NE(permissions.find("<id>3</id>"), std::string::npos) << "the keystore's domain";
  EXPECT_EQ(runTool("list " + ks.string()).code, 0);
}

TEST_F(KeystoreTest, ASettingsFileWithAnAliasCycleIsRefusedAndKept) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string()).code, 0);
  // A node that contains itself: walking it never ends (yaml-cpp's own reader overflowed).
  const std::string settings = "organization: &a [*a]\ndomain_id: 0\nnext_serial: 2\n";
  std::ofstream(ks / "keystore.yaml") << settings;
  const ToolRun add = runTool("add " + ks.string() + " camera_1");
  EXPECT_EQ(add.code, 1) << add.output;
  EXPECT_NE(add.output.find("keystore.yaml"), std::string::npos) << add.output;
  EXPECT_NE(add.output.find("alias"), std::string::npos) << add.output;
  EXPECT_FALSE(fs::exists(ks / "identities/camera_1"));
  EXPECT_EQ(readFile(ks / "keystore.yaml"), settings);
}

TEST_F(KeystoreTest, CheckDiagnosesCrossVendorPairs) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string()).code, 0);
  const ToolRun good = runTool("check " + ks.string() + " --cyclonedds shore --fastdds vehicle");
  EXPECT_EQ(good.code, 0) << good.output;
  EXPECT_NE(good.output.find("supported"), std::string::npos) << good.output;
  const ToolRun bad = runTool("check " + ks.string() + " --cyclonedds vehicle --fastdds shore");
  EXPECT_EQ(bad.code, 1) << bad.output;
  // The suggested name must itself pass the check.
  const size_t at = bad.output.find("An identity named '");
  ASSERT_NE(at, std::string::npos) << bad.output;
  const size_t start = at + 19;
  const std::string suggestion = bad.output.substr(start, bad.output.find('\'', start) - start);
  EXPECT_EQ(crossVendorProblem("auv-inspect", {suggestion}, {"shore"}), "") << suggestion;
  const ToolRun same = runTool("check " + ks.string() + " --cyclonedds shore --fastdds shore");
  EXPECT_EQ(same.code, 1);
  EXPECT_NE(same.output.find("the same identity on both vendors"), std::string::npos);
  EXPECT_EQ(runTool("check " + ks.string() + " --cyclonedds shore").code, 2);
}

TEST_F(KeystoreTest, BackendNamesTheMissingFile) {
  const fs::path ks = dir_ / "keys";
  ASSERT_EQ(runTool("init " + ks.string()).code, 0);
  fs::remove(ks / "identities/vehicle/key.pem");
  interfaces::SecurityIdentity identity{ks.string(), "vehicle", true};
  try {
    interfaces::resolveSecurity(identity);
    ADD_FAILURE() << "a missing key must be an error under Enforce";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((ks / "identities/vehicle/key.pem").string()),
              std::string::npos)
        << e.what();
  }
  identity.enforce = false;
  EXPECT_FALSE(interfaces::resolveSecurity(identity).has_value()) << "Permissive: unsecured";
  identity.identity = "shore";
  const auto files = interfaces::resolveSecurity(identity);
  ASSERT_TRUE(files.has_value());
  EXPECT_EQ(files->private_key, (ks / "identities/shore/key.pem").string());
}

TEST(SecurityEnvironment, ReadsAndValidatesTheVariables) {
  ::unsetenv("AUV_SECURITY_KEYSTORE");
  EXPECT_FALSE(interfaces::securityFromEnvironment().has_value());
  ::setenv("AUV_SECURITY_KEYSTORE", "/some/keystore", 1);
  ::unsetenv("AUV_SECURITY_IDENTITY");
  EXPECT_THROW(
      {
        try {
          interfaces::securityFromEnvironment();
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("AUV_SECURITY_IDENTITY"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  ::setenv("AUV_SECURITY_IDENTITY", "shore", 1);
  ::setenv("AUV_SECURITY_STRATEGY", "Lenient", 1);
  EXPECT_THROW(interfaces::securityFromEnvironment(), std::invalid_argument);
  ::setenv("AUV_SECURITY_STRATEGY", "Permissive", 1);
  const auto identity = interfaces::securityFromEnvironment();
  ASSERT_TRUE(identity.has_value());
  EXPECT_EQ(identity->keystore, "/some/keystore");
  EXPECT_EQ(identity->identity, "shore");
  EXPECT_FALSE(identity->enforce);
  ::unsetenv("AUV_SECURITY_STRATEGY");
  EXPECT_TRUE(interfaces::securityFromEnvironment()->enforce) << "Enforce is the default";
  ::unsetenv("AUV_SECURITY_KEYSTORE");
  ::unsetenv("AUV_SECURITY_IDENTITY");
}

}  // namespace
}  // namespace auv::bringup
