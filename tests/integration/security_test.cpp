// DDS Security (the secure profiles, docs/networking.md "Security"): real teleop_server and
// teleop_master processes and in-process participants on loopback, each test on a domain id of
// its own (tests/support/domains.hpp). The certificates, keys and signed documents are made
// once per test process by deploy/make_security.sh into a temporary folder (nothing secret is
// committed) and removed at the end.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

namespace fs = std::filesystem;
using eprosima::fastdds::dds::SampleInfo;

const std::string kToolScene = scene_file("tool_only.yaml");
const std::string kMakeSecurity = std::string(TELEOP_SOURCE_DIR) + "/deploy/make_security.sh";

/// Arguments of a secure tool-scene server on `domain` writing `summary_json` at exit.
std::vector<std::string> secure_server_args(int domain, const std::string& dir,
                                            const std::string& summary_json) {
  return {
      "--profile",  "secure", "--security-dir", dir,          "--domain", std::to_string(domain),
      "--duration", "60",     "--summary-json", summary_json, "--scene",  kToolScene};
}

dds::ParticipantOptions secure_options(int domain, const std::string& dir,
                                       const std::string& identity, const std::string& name) {
  dds::ParticipantOptions o{"secure", domain, name};
  o.network.security = {dir, "--security-dir", identity, "--identity"};
  return o;
}

MasterCommand command(std::uint64_t seq, double x) {
  MasterCommand c;
  c.seq(seq);
  c.send_time_ns(now_ns());
  c.position_m() = {x, 0.0, 0.4};
  c.orientation_wxyz() = {1, 0, 0, 0};
  c.enabled(true);
  return c;
}

bool wait_until(double timeout_s, const std::function<bool()>& done) {
  const auto t0 = now_ns();
  while (seconds_between(t0, now_ns()) < timeout_s) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

/// A participant that listens to what the server publishes and counts it.
class Listener {
 public:
  explicit Listener(const dds::ParticipantOptions& o)
      : participant_(o),
        state_(participant_, dds::topics::kSlaveState,
               [this](const SlaveState&, const SampleInfo&) { ++states; }),
        scene_(participant_, dds::topics::kScene,
               [this](const SceneDescription&, const SampleInfo&) { ++scenes; }),
        stats_(participant_, dds::topics::kServerStats,
               [this](const ServerStats&, const SampleInfo&) { ++stats; }),
        events_(participant_, dds::topics::kEvents,
                [this](const Event&, const SampleInfo&) { ++events; }) {}

  dds::Participant& participant() { return participant_; }
  int matched_writers() const {
    return state_.matched() + scene_.matched() + stats_.matched() + events_.matched();
  }
  int total() const { return states + scenes + stats + events; }

  std::atomic<int> states{0}, scenes{0}, stats{0}, events{0};

 private:
  dds::Participant participant_;
  dds::Reader<SlaveStatePubSubType> state_;
  dds::Reader<SceneDescriptionPubSubType> scene_;
  dds::Reader<ServerStatsPubSubType> stats_;
  dds::Reader<EventPubSubType> events_;
};

/// A participant that listens and also tries to command the slave.
class Outsider : public Listener {
 public:
  explicit Outsider(const dds::ParticipantOptions& o)
      : Listener(o), writer_(participant(), dds::topics::kMasterCommand) {}
  void send(std::uint64_t seq) {
    auto c = command(seq, 0.5);
    writer_.write(c);
  }
  int matched_readers() const { return writer_.matched(); }

 private:
  dds::Writer<MasterCommandPubSubType> writer_;
};

class Security : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = temp_path("sec", "certs");
    fs::remove_all(dir_);
    have_openssl_ = std::system("command -v openssl > /dev/null 2>&1") == 0;
    if (!have_openssl_) return;
    const std::string cmd = "bash '" + kMakeSecurity + "' '" + dir_ + "' > '" + dir_ + ".log' 2>&1";
    status_ = std::system(cmd.c_str());
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_);
    fs::remove(dir_ + ".log");
  }
  void SetUp() override {
    if (!have_openssl_) GTEST_SKIP() << "openssl is not installed (deploy/setup.sh installs it)";
    ASSERT_EQ(status_, 0) << kMakeSecurity << " failed:\n" << Process::slurp(dir_ + ".log");
  }
  static std::string dir_;
  static int status_;
  static bool have_openssl_;
};
std::string Security::dir_;
int Security::status_ = -1;
bool Security::have_openssl_ = false;

// (1) Without our credentials, a participant sees nothing and commands nothing: one with no
// security at all (the plain loopback profile) and one with valid files of another CA (the
// "nobody" identity of DIR/other), both on the server's domain while a credentialed observer
// shows the server is publishing.
TEST_F(Security, ParticipantsWithoutOurCredentialsSeeNothingAndCommandNothing) {
  const int domain = domains::kSecureOutsiders;
  const std::string server_json = temp_path("sec", "outsiders_server.json");
  Process server(kServerBinary, secure_server_args(domain, dir_, server_json), "sec_out_server");
  Listener observer(secure_options(domain, dir_, "observer", "sec_observer"));
  ASSERT_TRUE(wait_until(20.0, [&] { return observer.states > 100; }))
      << "the credentialed observer got no SlaveState: " << server.err();

  Outsider plain(dds::ParticipantOptions{"loopback", domain, "sec_plain"});
  Outsider stranger(secure_options(domain, dir_ + "/other", "nobody", "sec_stranger"));
  const int states_before = observer.states;
  // 3 s of commands at 500 Hz from both
  std::uint64_t seq = 0;
  const auto t0 = now_ns();
  while (seconds_between(t0, now_ns()) < 3.0) {
    ++seq;
    plain.send(seq);
    stranger.send(seq);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  // the server kept publishing to the observer all along
  EXPECT_GT(observer.states - states_before, 500);
  EXPECT_EQ(observer.scenes, 1);
  EXPECT_EQ(plain.total(), 0) << "states " << plain.states << " scenes " << plain.scenes
                              << " stats " << plain.stats << " events " << plain.events;
  EXPECT_EQ(stranger.total(), 0) << "states " << stranger.states << " scenes " << stranger.scenes
                                 << " stats " << stranger.stats << " events " << stranger.events;
  EXPECT_EQ(plain.matched_writers(), 0);
  EXPECT_EQ(stranger.matched_writers(), 0);
  EXPECT_EQ(plain.matched_readers(), 0);
  EXPECT_EQ(stranger.matched_readers(), 0);

  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(server_json);
  EXPECT_EQ(json_value(s, "commands_received"), 0) << s;
}

// (2) An observer with valid credentials reads the server's topics, but its permissions let it
// publish nothing: the DataWriter of teleop/master_command (or of the server's topics) cannot
// be created, and the server receives no command.
TEST_F(Security, ObserverReadsStateButCannotWriteCommands) {
  const int domain = domains::kSecureObserver;
  const std::string server_json = temp_path("sec", "observer_server.json");
  Process server(kServerBinary, secure_server_args(domain, dir_, server_json), "sec_obs_server");
  Listener observer(secure_options(domain, dir_, "observer", "sec_observer"));
  ASSERT_TRUE(wait_until(20.0, [&] { return observer.states > 200 && observer.stats > 0; }))
      << "states " << observer.states << " stats " << observer.stats << "\n"
      << server.err();
  EXPECT_EQ(observer.scenes, 1);
  EXPECT_GT(observer.events, 0);  // the server's start-up events (transient local)

  auto& p = observer.participant();
  EXPECT_THROW(dds::Writer<MasterCommandPubSubType>(p, dds::topics::kMasterCommand), dds::DdsError);
  EXPECT_THROW(dds::Writer<SlaveStatePubSubType>(p, dds::topics::kSlaveState), dds::DdsError);
  // nor retune a master: live tuning is the operator role's (and the master's answers its own)
  EXPECT_THROW(dds::Writer<TuningRequestPubSubType>(p, dds::topics::kTuning), dds::DdsError);
  EXPECT_THROW(dds::Writer<TuningStatusPubSubType>(p, dds::topics::kTuningStatus), dds::DdsError);
  // nor pose as a master describing its experiment
  EXPECT_THROW(dds::Writer<ExperimentDescriptionPubSubType>(p, dds::topics::kExperiment),
               dds::DdsError);
  {
    // an operator (a device driver, teleop_viewer --drive) may write the device state and
    // tuning requests, and still not commands
    Listener op(secure_options(domain, dir_, "operator", "sec_operator"));
    auto& po = op.participant();
    EXPECT_NO_THROW(dds::Writer<TuningRequestPubSubType>(po, dds::topics::kTuning));
    EXPECT_NO_THROW(dds::Writer<DeviceStatePubSubType>(po, dds::topics::kDeviceState));
    EXPECT_THROW(dds::Writer<MasterCommandPubSubType>(po, dds::topics::kMasterCommand),
                 dds::DdsError);
  }
  // the same through the raw API: access control refuses the DataWriter
  auto* topic = p.topic(dds::topics::kMasterCommand.name,
                        eprosima::fastdds::dds::TypeSupport(new MasterCommandPubSubType()));
  EXPECT_EQ(p.publisher()->create_datawriter(
                topic, dds::writer_qos(p.publisher(), dds::topics::kMasterCommand.qos)),
            nullptr);

  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(server_json);
  EXPECT_EQ(json_value(s, "commands_received"), 0) << s;
}

// (3) A whole session with security on: server and master, 3000 commands at 1 kHz.
TEST_F(Security, SecureSessionRunsStable) {
  const int domain = domains::kSecureSession;
  const std::string d = std::to_string(domain);
  const std::string master_json = temp_path("sec", "session_master.json");
  const std::string server_json = temp_path("sec", "session_server.json");
  Process server(kServerBinary, secure_server_args(domain, dir_, server_json), "sec_s_server");
  Process master(kMasterBinary,
                 {"--profile", "secure", "--security-dir", dir_, "--domain", d, "--samples", "3000",
                  "--summary-json", master_json},
                 "sec_s_master");
  ASSERT_EQ(master.wait_for(50.0), 0) << master.err() << master.out();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();

  const std::string m = Process::slurp(master_json);
  const double sent = json_value(m, "sent"), received = json_value(m, "received");
  std::printf("secure session: commands %.0f/%.0f received, rtt p50 %.3f ms p99 %.3f ms\n",
              received, sent, json_nested(m, "rtt_ms", "p50"), json_nested(m, "rtt_ms", "p99"));
  // the 3000 cycles asked for and the force's fade-out at the end
  EXPECT_EQ(sent, 3000 + json_value(m, "closing_cycles")) << m;
  EXPECT_GE(received, 0.99 * sent) << m;
  EXPECT_EQ(json_text(m, "verdict"), "stable") << m;
  const double p99 = json_nested(m, "rtt_ms", "p99");
  EXPECT_GT(p99, 0.0) << m;
  EXPECT_LT(p99, 50.0) << m;  // generous: a loaded 2-core machine
  const std::string s = Process::slurp(server_json);
  EXPECT_GE(json_value(s, "commands_received"), received) << s;
}

// (4) Missing or wrong files stop the program before DDS starts, with exit status 2 and a
// message naming the flag, the path and what is missing.
TEST_F(Security, BadSecurityFilesExit2NamingFlagPathAndWhat) {
  const std::string d = std::to_string(domains::kSecureBadFiles);
  auto run = [&](const std::string& exe, std::vector<std::string> args, const std::string& tag) {
    args.insert(args.end(), {"--domain", d});
    Process p(exe, args, tag);
    const int rc = p.wait_for(20.0);
    return std::make_pair(rc, p.err());
  };
  // a secure profile without --security-dir
  auto [rc, err] = run(kServerBinary, {"--profile", "secure"}, "sec_bad1");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("--security-dir"), std::string::npos) << err;
  EXPECT_NE(err.find("TELEOP_SECURITY_DIR"), std::string::npos) << err;

  // a folder that does not exist
  std::tie(rc, err) =
      run(kMasterBinary, {"--profile", "secure", "--security-dir", "/no/such/dir"}, "sec_bad2");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("--security-dir '/no/such/dir'"), std::string::npos) << err;
  EXPECT_NE(err.find("no such directory"), std::string::npos) << err;

  // an identity that is not there: the message lists those that are
  std::tie(rc, err) =
      run(kMasterBinary, {"--profile", "secure", "--security-dir", dir_, "--identity", "alice"},
          "sec_bad3");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("no identity 'alice'"), std::string::npos) << err;
  EXPECT_NE(err.find("master, observer, operator, server"), std::string::npos) << err;

  // a copy of the folder without the master's key, and with a garbage permissions CA
  const std::string copy = temp_path("sec", "copy");
  fs::remove_all(copy);
  fs::copy(dir_, copy, fs::copy_options::recursive);
  fs::remove(copy + "/master/identity.key.pem");
  std::tie(rc, err) =
      run(kMasterBinary, {"--profile", "secure", "--security-dir", copy}, "sec_bad4");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("--security-dir '" + copy + "'"), std::string::npos) << err;
  EXPECT_NE(err.find("missing " + copy + "/master/identity.key.pem"), std::string::npos) << err;
  EXPECT_NE(err.find("private key of 'master'"), std::string::npos) << err;
  std::ofstream(copy + "/permissions_ca.cert.pem") << "not a certificate\n";
  std::tie(rc, err) =
      run(kServerBinary, {"--profile", "secure", "--security-dir", copy}, "sec_bad5");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find(copy + "/permissions_ca.cert.pem does not hold the permissions CA"),
            std::string::npos)
      << err;
  // the environment variable is named when it gave the folder
  setenv("TELEOP_SECURITY_DIR", copy.c_str(), 1);
  std::tie(rc, err) = run(kServerBinary, {"--profile", "secure"}, "sec_bad6");
  unsetenv("TELEOP_SECURITY_DIR");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("TELEOP_SECURITY_DIR='" + copy + "'"), std::string::npos) << err;
  fs::remove_all(copy);

  // security flags on a profile without security
  std::tie(rc, err) = run(kServerBinary, {"--security-dir", dir_}, "sec_bad7");
  EXPECT_EQ(rc, 2) << err;
  EXPECT_NE(err.find("does not apply to profile 'loopback'"), std::string::npos) << err;
  EXPECT_NE(err.find("secure"), std::string::npos) << err;
}

// (5) Files that look right but do not verify: the identity of another CA put into our folder.
// Fast DDS refuses to create the participant; the program says which identity and folder and
// exits non-zero.
TEST_F(Security, IdentityOfAnotherCaIsRefusedAtStart) {
  const std::string copy = temp_path("sec", "stranger");
  fs::remove_all(copy);
  fs::copy(dir_, copy, fs::copy_options::recursive);
  fs::copy(dir_ + "/other/nobody", copy + "/nobody", fs::copy_options::recursive);
  Process master(kMasterBinary,
                 {"--profile", "secure", "--security-dir", copy, "--identity", "nobody", "--domain",
                  std::to_string(domains::kSecureStranger), "--samples", "100"},
                 "sec_stranger");
  const int rc = master.wait_for(20.0);
  const std::string err = master.err();
  EXPECT_NE(rc, 0) << err;
  EXPECT_NE(rc, -1) << "still running: " << err;
  EXPECT_NE(err.find("DDS Security refused identity 'nobody'"), std::string::npos) << err;
  EXPECT_NE(err.find("--security-dir '" + copy + "'"), std::string::npos) << err;
  // the reason, found with OpenSSL: the certificate's issuer is not our identity CA
  EXPECT_NE(err.find(copy + "/nobody/identity.cert.pem does not verify with the identity CA"),
            std::string::npos)
      << err;

  // the server's key in the master's folder: the key is not the certificate's
  fs::copy_file(copy + "/server/identity.key.pem", copy + "/master/identity.key.pem",
                fs::copy_options::overwrite_existing);
  Process swapped(kMasterBinary,
                  {"--profile", "secure", "--security-dir", copy, "--domain",
                   std::to_string(domains::kSecureStranger), "--samples", "100"},
                  "sec_swapped");
  const int rc2 = swapped.wait_for(20.0);
  const std::string err2 = swapped.err();
  fs::remove_all(copy);
  EXPECT_NE(rc2, 0) << err2;
  EXPECT_NE(rc2, -1) << "still running: " << err2;
  EXPECT_NE(err2.find(copy + "/master/identity.key.pem is not the private key of " + copy +
                      "/master/identity.cert.pem"),
            std::string::npos)
      << err2;
}

// make_security.sh --hours N: certificates and permissions valid from 5 minutes before they are
// made to N hours after, which a secure server accepts; a bad N is refused with exit status 2.
TEST(SecurityScript, ShortLivedIdentitiesLastTheHoursAsked) {
  if (std::system("command -v openssl > /dev/null 2>&1") != 0) GTEST_SKIP() << "no openssl";
  const std::string dir = temp_path("sec", "short");
  fs::remove_all(dir);
  const std::string log = dir + ".log";
  ASSERT_EQ(std::system(("bash '" + kMakeSecurity + "' --hours 2 --no-other --identity " +
                         "server:server '" + dir + "' > '" + log + "' 2>&1")
                            .c_str()),
            0)
      << Process::slurp(log);
  // the certificate's validity in seconds: 2 h plus the 5 minutes before
  const std::string cert = dir + "/server/identity.cert.pem";
  const std::string span = dir + ".span";
  const std::string cmd = "bash -c 'a=$(openssl x509 -in " + cert +
                          " -noout -startdate | cut -d= -f2); b=$(openssl x509 -in " + cert +
                          " -noout -enddate | cut -d= -f2); echo $(( $(date -d \"$b\" +%s) - "
                          "$(date -d \"$a\" +%s) ))' > " +
                          span;
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(std::atoi(Process::slurp(span).c_str()), 2 * 3600 + 300) << Process::slurp(span);
  const std::string permissions = Process::slurp(dir + "/server/permissions.xml");
  EXPECT_NE(permissions.find("<not_after>"), std::string::npos) << permissions;
  // a secure server accepts the files (DDS Security checks both validity periods at start)
  Process server(kServerBinary,
                 {"--profile", "secure", "--security-dir", dir, "--domain",
                  std::to_string(domains::kSecureShortLived), "--duration", "0.5", "--scene",
                  scene_file("tool_only.yaml"), "--quiet"},
                 "sec_short");
  EXPECT_EQ(server.wait_for(30.0), 0) << server.err();
  const int bad = std::system(
      ("bash '" + kMakeSecurity + "' --hours 0 '" + dir + "' > '" + log + "' 2>&1").c_str());
  EXPECT_EQ(WEXITSTATUS(bad), 2);
  EXPECT_NE(Process::slurp(log).find("--hours '0' is not an integer in [1, 8760]"),
            std::string::npos);
  fs::remove_all(dir);
  fs::remove(log);
  fs::remove(span);
}

}  // namespace
}  // namespace teleop::test
