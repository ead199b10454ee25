// TLS, mutual TLS and bearer tokens end to end. Certificates come from scripts/make-test-certs
// (openssl, EC P-256) in a temporary directory made once for the suite; every server is a real
// PlanningServer (or a small probe service with the same credentials) on 127.0.0.1:0.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "chasles/robot/error.h"
#include "chasles/server/planning_server.h"
#include "chasles/server/security.h"
#include "chasles/v1/chasles.grpc.pb.h"
#include "server_fixture.h"

namespace chasles {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::LoadRequest;
using testing::ReadText;

constexpr char kPlanToken[] = "plan-token-5f0c2a9e71d34b8c";
constexpr char kCommitToken[] = "commit-token-94e1b7d02c6a4f35";

/// Certificates and a tokens file, made once for all tests.
class SecurityTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::path(::testing::TempDir()) / ("chasles_tls_" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    const std::string command = std::string(CHASLES_SOURCE_DIR) + "/scripts/make-test-certs '" + dir_->string() +
                                "' > '" + (*dir_ / "make-test-certs.log").string() + "' 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command << "\n" << ReadText((*dir_ / "make-test-certs.log").string());
    std::ofstream tokens(Path("tokens.txt"));
    tokens << "# NAME ROLE TOKEN\n\n"
           << "planner  plan   " << kPlanToken << "\n"
           << "  # an indented comment\n"
           << "operator commit " << kCommitToken << "\n";
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete dir_;
  }

  static std::string Path(const std::string& name) { return (*dir_ / name).string(); }

  static SecurityOptions Tls() {
    SecurityOptions options;
    options.tls_cert = Path("server.pem");
    options.tls_key = Path("server.key");
    return options;
  }
  static SecurityOptions MutualTls() {
    SecurityOptions options = Tls();
    options.tls_client_ca = Path("ca.pem");
    return options;
  }

  static std::unique_ptr<PlanningServer> Start(const SecurityOptions& security) {
    ServerOptions options;
    options.listen = "127.0.0.1:0";
    options.threads = 2;
    options.log_requests = false;
    options.security = security;
    return std::make_unique<PlanningServer>(options);
  }

  /// A TLS channel trusting `ca` (a file in the suite's directory), with a client certificate
  /// `client` ("" = none), to localhost (the server certificate's SAN).
  static std::shared_ptr<grpc::Channel> TlsChannel(int port, const std::string& ca = "ca.pem",
                                                   const std::string& client = "") {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadText(Path(ca));
    if (!client.empty()) {
      ssl.pem_cert_chain = ReadText(Path(client + ".pem"));
      ssl.pem_private_key = ReadText(Path(client + ".key"));
    }
    return grpc::CreateChannel("localhost:" + std::to_string(port), grpc::SslCredentials(ssl));
  }
  static std::shared_ptr<grpc::Channel> PlainChannel(int port) {
    return grpc::CreateChannel("127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials());
  }

  static void Prepare(grpc::ClientContext* context, const std::string& token, int seconds = 10) {
    context->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
    if (!token.empty()) context->AddMetadata("authorization", "Bearer " + token);
  }

  static grpc::Status ListPlanners(const std::shared_ptr<grpc::Channel>& channel, const std::string& token = "") {
    grpc::ClientContext context;
    Prepare(&context, token);
    v1::ListPlannersResponse response;
    return v1::Planning::NewStub(channel)->ListPlanners(&context, v1::ListPlannersRequest(), &response);
  }

  static grpc::Status Plan(const std::shared_ptr<grpc::Channel>& channel, const std::string& token,
                           v1::PlanResponse* response) {
    grpc::ClientContext context;
    Prepare(&context, token, 60);
    return v1::Planning::NewStub(channel)->Plan(&context, LoadRequest("panda_table"), response);
  }

  /// grpc.health.v1.Health/Check (service ""), without a token; SERVING is bytes 08 01.
  static grpc::Status Health(const std::shared_ptr<grpc::Channel>& channel, std::string* bytes) {
    grpc::GenericStub stub(channel);
    grpc::ClientContext context;
    Prepare(&context, "");
    grpc::Slice empty(std::string{});
    grpc::ByteBuffer request(&empty, 1);
    grpc::ByteBuffer response;
    std::promise<grpc::Status> done;
    stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                   [&done](grpc::Status status) { done.set_value(std::move(status)); });
    const grpc::Status status = done.get_future().get();
    std::vector<grpc::Slice> slices;
    bytes->clear();
    if (status.ok() && response.Dump(&slices).ok()) {
      for (const grpc::Slice& slice : slices) bytes->append(reinterpret_cast<const char*>(slice.begin()), slice.size());
    }
    return status;
  }

  static std::string InvalidMessage(const SecurityOptions& options) {
    try {
      options.Validate();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return e.what();
    }
    return "(accepted)";
  }

  static std::string TokensMessage(const std::string& content) {
    const std::string path = Path("bad-tokens.txt");
    std::ofstream(path) << content;
    SecurityOptions options;
    options.tokens_file = path;
    return InvalidMessage(options);
  }

  static inline fs::path* dir_ = nullptr;
};

// --- options and files ----------------------------------------------------------------------------

TEST_F(SecurityTest, ValidateNamesTheFlagTheFileAndTheRule) {
  EXPECT_EQ(InvalidMessage(SecurityOptions()), "(accepted)");
  EXPECT_EQ(InvalidMessage(MutualTls()), "(accepted)");

  SecurityOptions only_cert;
  only_cert.tls_cert = Path("server.pem");
  EXPECT_THAT(InvalidMessage(only_cert), HasSubstr("--tls-cert is set but --tls-key is not"));

  SecurityOptions ca_without_tls;
  ca_without_tls.tls_client_ca = Path("ca.pem");
  EXPECT_THAT(InvalidMessage(ca_without_tls), HasSubstr("--tls-client-ca"));

  SecurityOptions missing = Tls();
  missing.tls_cert = Path("no-such.pem");
  EXPECT_THAT(InvalidMessage(missing), HasSubstr("--tls-cert '" + Path("no-such.pem") + "' cannot be read"));

  SecurityOptions not_pem = Tls();
  not_pem.tls_cert = Path("tokens.txt");
  EXPECT_THAT(InvalidMessage(not_pem), HasSubstr("holds no PEM certificate"));

  SecurityOptions key_not_pem = Tls();
  key_not_pem.tls_key = Path("server.pem");
  EXPECT_THAT(InvalidMessage(key_not_pem), HasSubstr("--tls-key '" + Path("server.pem") + "' holds no unencrypted PEM private key"));

  SecurityOptions mismatch = Tls();
  mismatch.tls_key = Path("client.key");
  EXPECT_THAT(InvalidMessage(mismatch), HasSubstr("is not the private key of the first certificate in --tls-cert"));

  SecurityOptions bad_ca = MutualTls();
  bad_ca.tls_client_ca = Path("server.key");
  EXPECT_THAT(InvalidMessage(bad_ca), HasSubstr("--tls-client-ca '" + Path("server.key") + "' holds no PEM certificate"));

  // The server refuses to start with the same message.
  try {
    Start(mismatch);
    ADD_FAILURE() << "a server started with a key that does not match its certificate";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("--tls-key"));
  }
}

TEST_F(SecurityTest, TokensFileErrorsNameTheLineAndNeverTheToken) {
  EXPECT_THAT(TokensMessage("# nothing\n\n"), HasSubstr("holds no tokens"));
  const std::string two_fields = TokensMessage("alice plan\n");
  EXPECT_THAT(two_fields, HasSubstr("line 1 has 2 fields; expected 3: NAME ROLE TOKEN"));
  const std::string role = TokensMessage("# header\nalice admin abcdefghijklmnopqrstuvwxyz\n");
  EXPECT_THAT(role, HasSubstr("line 2: role 'admin' of 'alice' must be 'plan' or 'commit'"));
  EXPECT_THAT(role, ::testing::Not(HasSubstr("abcdefghijklmnop")));
  const std::string short_token = TokensMessage("alice plan s3cret\n");
  EXPECT_THAT(short_token, HasSubstr("the token of 'alice' has 6 characters; it must have at least 16"));
  EXPECT_THAT(short_token, ::testing::Not(HasSubstr("s3cret")));
  EXPECT_THAT(TokensMessage("alice plan abcdefghijklmnopqrstuvwxyz\nbob commit abcdefghijklmnopqrstuvwxyz\n"),
              HasSubstr("line 2: the token of 'bob' repeats the token of 'alice' (line 1)"));
}

TEST(Security, PermissionsOfEveryRpc) {
  for (const char* rpc : {"Plan", "Optimize", "InverseKinematics", "ListPlanners", "UploadRobot", "UploadScene",
                          "UpdateScene", "Coordinate", "Benchmark", "StopBenchmark", "Replan", "View",
                          "/chasles.v1.Planning/Plan"}) {
    EXPECT_EQ(RequiredPermission(rpc), Permission::kPlan) << rpc;
  }
  for (const char* rpc : {"CreateWorkcell", "CommitTrajectory", "Release", "/chasles.v1.Planning/Release",
                          "SomethingNew", "/other.Service/Plan", ""}) {
    EXPECT_EQ(RequiredPermission(rpc), Permission::kCommit) << rpc;
  }
  for (const char* rpc : {"/grpc.health.v1.Health/Check", "/grpc.health.v1.Health/Watch",
                          "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo"}) {
    EXPECT_EQ(RequiredPermission(rpc), Permission::kOpen) << rpc;
  }
}

TEST(Security, LoopbackAddresses) {
  for (const char* listen : {"127.0.0.1:50051", "127.0.0.1:0", "localhost:50051", "[::1]:50051", "127.1.2.3:1"}) {
    EXPECT_TRUE(IsLoopbackAddress(listen)) << listen;
  }
  for (const char* listen : {"0.0.0.0:50051", "[::]:50051", "10.0.0.7:50051", "robot-cell:50051"}) {
    EXPECT_FALSE(IsLoopbackAddress(listen)) << listen;
  }
}

// --- TLS --------------------------------------------------------------------------------------------

TEST_F(SecurityTest, PlanOverTlsAndPlaintextClientsAreRefused) {
  const auto server = Start(Tls());
  v1::PlanResponse response;
  const grpc::Status status = Plan(TlsChannel(server->port()), "", &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.outcome(), v1::SUCCESS) << response.message();
  EXPECT_GT(response.trajectory().points_size(), 1);

  EXPECT_FALSE(ListPlanners(PlainChannel(server->port())).ok()) << "a plaintext client reached a TLS server";
  EXPECT_FALSE(ListPlanners(TlsChannel(server->port(), "other-ca.pem")).ok())
      << "a client trusting another CA accepted the server's certificate";
}

TEST_F(SecurityTest, MutualTlsNeedsATrustedClientCertificate) {
  const auto server = Start(MutualTls());
  EXPECT_FALSE(ListPlanners(TlsChannel(server->port())).ok()) << "no client certificate, yet accepted";
  EXPECT_FALSE(ListPlanners(TlsChannel(server->port(), "ca.pem", "other-client")).ok())
      << "a client certificate of an untrusted CA was accepted";
  const grpc::Status status = ListPlanners(TlsChannel(server->port(), "ca.pem", "client"));
  EXPECT_TRUE(status.ok()) << status.error_message();
}

// --- tokens -----------------------------------------------------------------------------------------

TEST_F(SecurityTest, TokensAndRolesOverTls) {
  SecurityOptions security = Tls();
  security.tokens_file = Path("tokens.txt");
  const auto server = Start(security);
  const auto channel = TlsChannel(server->port());

  grpc::Status status = ListPlanners(channel);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(status.error_message(), HasSubstr("missing 'authorization: Bearer <token>' metadata"));
  status = ListPlanners(channel, "not-a-token-of-this-server");
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_THAT(status.error_message(), HasSubstr("unknown token"));
  {
    grpc::ClientContext context;
    Prepare(&context, "");
    context.AddMetadata("authorization", std::string("Basic ") + kPlanToken);
    v1::ListPlannersResponse response;
    status = v1::Planning::NewStub(channel)->ListPlanners(&context, v1::ListPlannersRequest(), &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_THAT(status.error_message(), HasSubstr("must be 'Bearer <token>'"));
  }
  {  // A streaming call is refused the same way.
    grpc::ClientContext context;
    Prepare(&context, "");
    auto reader = v1::Planning::NewStub(channel)->Benchmark(&context, v1::BenchmarkRequest());
    v1::BenchmarkResponse message;
    while (reader->Read(&message)) {
    }
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::UNAUTHENTICATED);
  }

  // Health needs no token.
  std::string health;
  status = Health(channel, &health);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(health, std::string("\x08\x01", 2));

  // A plan token plans, but may not touch workcells.
  v1::PlanResponse plan;
  status = Plan(channel, kPlanToken, &plan);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(plan.outcome(), v1::SUCCESS) << plan.message();
  auto stub = v1::Planning::NewStub(channel);
  v1::CommitTrajectoryRequest commit;
  commit.set_workcell("cell");
  commit.set_robot_name("panda-1");
  *commit.mutable_trajectory() = plan.trajectory();
  {
    grpc::ClientContext context;
    Prepare(&context, kPlanToken);
    v1::CommitTrajectoryResponse response;
    status = stub->CommitTrajectory(&context, commit, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    EXPECT_EQ(status.error_message(),
              "CommitTrajectory needs a token with role 'commit'; the token of 'planner' has role 'plan'");
  }
  {
    grpc::ClientContext context;
    Prepare(&context, kPlanToken);
    v1::CreateWorkcellRequest request;
    request.set_name("cell");
    v1::CreateWorkcellResponse response;
    EXPECT_EQ(stub->CreateWorkcell(&context, request, &response).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }

  // A commit token does both.
  {
    grpc::ClientContext context;
    Prepare(&context, kCommitToken);
    v1::CreateWorkcellRequest request;
    request.set_name("cell");
    v1::CreateWorkcellResponse response;
    status = stub->CreateWorkcell(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  {
    grpc::ClientContext context;
    Prepare(&context, kCommitToken);
    v1::CommitTrajectoryResponse response;
    status = stub->CommitTrajectory(&context, commit, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_FALSE(response.reservation_id().empty());
  }
  {
    grpc::ClientContext context;
    Prepare(&context, kCommitToken);
    v1::ReleaseRequest request;
    request.set_workcell("cell");
    request.set_robot_name("panda-1");
    v1::ReleaseResponse response;
    status = stub->Release(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.released(), 1u);
  }
  EXPECT_TRUE(ListPlanners(channel, kCommitToken).ok());
}

TEST_F(SecurityTest, TokensOverPlaintextLoopback) {
  SecurityOptions security;
  security.tokens_file = Path("tokens.txt");
  const auto server = Start(security);
  const auto channel = PlainChannel(server->port());
  EXPECT_EQ(ListPlanners(channel).error_code(), grpc::StatusCode::UNAUTHENTICATED);
  const grpc::Status status = ListPlanners(channel, kPlanToken);
  EXPECT_TRUE(status.ok()) << status.error_message();
  std::string health;
  EXPECT_TRUE(Health(channel, &health).ok());
}

// --- identity -----------------------------------------------------------------------------------------

/// A service with the same credentials as the server, recording who called and what the handler's
/// own Authorize() says about CommitTrajectory.
class IdentityProbe final : public v1::Planning::CallbackService {
 public:
  explicit IdentityProbe(const AccessControl& access) : access_(access) {}
  grpc::ServerUnaryReactor* ListPlanners(grpc::CallbackServerContext* context, const v1::ListPlannersRequest*,
                                         v1::ListPlannersResponse*) override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      identity_ = access_.IdentifyClient(*context);
      commit_ = access_.Authorize(*context, "CommitTrajectory");
    }
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    reactor->Finish(grpc::Status::OK);
    return reactor;
  }
  ClientIdentity identity() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return identity_;
  }
  grpc::Status commit() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return commit_;
  }

 private:
  const AccessControl& access_;
  mutable std::mutex mutex_;
  ClientIdentity identity_;
  grpc::Status commit_;
};

struct ProbeServer {
  explicit ProbeServer(const SecurityOptions& options)
      : access(options,
               [this](const AccessRefusal& refusal) {
                 std::lock_guard<std::mutex> lock(refusals_mutex);
                 refusals.push_back(refusal);
               }),
        probe(access) {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", access.MakeServerCredentials(), &port);
    builder.RegisterService(&probe);
    server = builder.BuildAndStart();
  }
  ~ProbeServer() { server->Shutdown(); }
  std::vector<AccessRefusal> Refusals() {
    std::lock_guard<std::mutex> lock(refusals_mutex);
    return refusals;
  }
  std::mutex refusals_mutex;
  std::vector<AccessRefusal> refusals;
  AccessControl access;
  IdentityProbe probe;
  int port = 0;
  std::unique_ptr<grpc::Server> server;
};

TEST_F(SecurityTest, IdentityIsTheTokenNameElseTheCertificateElseThePeer) {
  {
    ProbeServer mtls(MutualTls());
    ASSERT_TRUE(ListPlanners(TlsChannel(mtls.port, "ca.pem", "client")).ok());
    const ClientIdentity identity = mtls.probe.identity();
    EXPECT_EQ(identity.name, "chasles-client");
    EXPECT_EQ(identity.role, "");
    EXPECT_TRUE(identity.authenticated);
    EXPECT_TRUE(mtls.probe.commit().ok()) << "without --tokens every authenticated client may commit";
  }
  {
    SecurityOptions security = MutualTls();
    security.tokens_file = Path("tokens.txt");
    ProbeServer both(security);
    const auto channel = TlsChannel(both.port, "ca.pem", "client");
    ASSERT_TRUE(ListPlanners(channel, kPlanToken).ok());
    EXPECT_EQ(both.probe.identity().name, "planner");
    EXPECT_EQ(both.probe.identity().role, "plan");
    EXPECT_EQ(both.probe.commit().error_code(), grpc::StatusCode::PERMISSION_DENIED);
    // The next call on the same connection carries another token: nothing of the first remains.
    ASSERT_TRUE(ListPlanners(channel, kCommitToken).ok());
    EXPECT_EQ(both.probe.identity().name, "operator");
    EXPECT_EQ(both.probe.identity().role, "commit");
    EXPECT_TRUE(both.probe.commit().ok());
  }
  {
    ProbeServer plain{SecurityOptions()};
    ASSERT_TRUE(ListPlanners(PlainChannel(plain.port)).ok());
    const ClientIdentity identity = plain.probe.identity();
    EXPECT_THAT(identity.name, HasSubstr("127.0.0.1:"));
    EXPECT_FALSE(identity.authenticated);
  }
}

TEST_F(SecurityTest, RefusedCallsAreReportedWithoutTheToken) {
  SecurityOptions security = Tls();
  security.tokens_file = Path("tokens.txt");
  ProbeServer server(security);
  const auto channel = TlsChannel(server.port);
  EXPECT_EQ(ListPlanners(channel, "no-such-token-of-this-server").error_code(), grpc::StatusCode::UNAUTHENTICATED);
  {
    grpc::ClientContext context;
    Prepare(&context, kPlanToken);
    v1::ReleaseResponse response;
    EXPECT_EQ(v1::Planning::NewStub(channel)->Release(&context, v1::ReleaseRequest(), &response).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  ASSERT_TRUE(ListPlanners(channel, kPlanToken).ok());
  const std::vector<AccessRefusal> refusals = server.Refusals();
  ASSERT_EQ(refusals.size(), 2u);
  EXPECT_EQ(refusals[0].rpc, "/chasles.v1.Planning/ListPlanners");
  EXPECT_EQ(refusals[0].code, grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(refusals[0].name, "");
  EXPECT_EQ(refusals[1].rpc, "/chasles.v1.Planning/Release");
  EXPECT_EQ(refusals[1].code, grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(refusals[1].name, "planner");
  for (const AccessRefusal& refusal : refusals) {
    EXPECT_THAT(refusal.message, ::testing::Not(HasSubstr("no-such-token")));
    EXPECT_THAT(refusal.message, ::testing::Not(HasSubstr(kPlanToken)));
  }
}

// --- CLI ----------------------------------------------------------------------------------------------

struct CliResult {
  int exit_code = -1;
  std::string output;
};

CliResult RunCli(const std::string& arguments, const std::string& environment = "") {
  static int calls = 0;
  const std::string log = ::testing::TempDir() + "/chasles_tls_cli_" + std::to_string(::getpid()) + "_" +
                          std::to_string(calls++) + ".txt";
  const std::string command =
      environment + " " + std::string(CHASLES_CLI) + " " + arguments + " > '" + log + "' 2>&1 < /dev/null";
  const int raw = std::system(command.c_str());
  CliResult result;
  result.exit_code = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  result.output = ReadText(log);
  std::remove(log.c_str());
  return result;
}

TEST_F(SecurityTest, CliOverMutualTlsWithTokens) {
  SecurityOptions security = MutualTls();
  security.tokens_file = Path("tokens.txt");
  const auto server = Start(security);
  const std::string tls = "--server localhost:" + std::to_string(server->port()) + " --tls-ca '" + Path("ca.pem") +
                          "' --tls-cert '" + Path("client.pem") + "' --tls-key '" + Path("client.key") + "' ";

  CliResult result = RunCli(tls + "health");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_THAT(result.output, HasSubstr("SERVING"));

  result = RunCli(tls + "planners");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("UNAUTHENTICATED"));

  result = RunCli(tls + "--token " + kPlanToken + " plan '" + testing::ExamplePath("requests/panda_table.json") + "'");
  EXPECT_EQ(result.exit_code, 0) << result.output;

  const std::string token_file = Path("cli-token.txt");
  std::ofstream(token_file) << kCommitToken << "\n";
  result = RunCli(tls + "--token-file '" + token_file + "' workcell cell");
  EXPECT_EQ(result.exit_code, 0) << result.output;

  result = RunCli(tls + "workcell cell", std::string("CHASLES_TOKEN=") + kPlanToken);
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("PERMISSION_DENIED"));
  EXPECT_THAT(result.output, ::testing::Not(HasSubstr(kPlanToken)));

  // Without the client certificate the TLS handshake fails.
  result = RunCli("--server localhost:" + std::to_string(server->port()) + " --timeout 5 --tls-ca '" + Path("ca.pem") +
                  "' --token " + kPlanToken + " planners");
  EXPECT_EQ(result.exit_code, 1) << result.output;

  // Tokens over plaintext to a loopback server (gRPC local credentials on both sides).
  SecurityOptions plaintext;
  plaintext.tokens_file = Path("tokens.txt");
  const auto local = Start(plaintext);
  const std::string at = "--server 127.0.0.1:" + std::to_string(local->port()) + " ";
  result = RunCli(at + "--token " + kCommitToken + " workcell cell");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  result = RunCli(at + "planners");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_THAT(result.output, HasSubstr("UNAUTHENTICATED"));

  // A bad flag combination is a usage error.
  result = RunCli("--tls-cert '" + Path("client.pem") + "' health");
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_THAT(result.output, HasSubstr("--tls-key"));
}

}  // namespace
}  // namespace chasles
