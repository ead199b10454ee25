#pragma once
// Shared helpers of the server tests: an in-process server on a free loopback port, a stub, and
// the example requests.

#include <chrono>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "chasles/server/planning_server.h"
#include "chasles/v1/chasles.grpc.pb.h"
#include "../read_file.h"

namespace chasles::testing {

inline std::string ExamplePath(const std::string& relative) {
  return std::string(CHASLES_SOURCE_DIR) + "/examples/" + relative;
}

inline std::string ReadText(const std::string& path) { return test::ReadFile(path); }

inline v1::PlanRequest LoadRequest(const std::string& name) {
  v1::PlanRequest request;
  const auto status =
      google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("requests/" + name + ".json")), &request);
  EXPECT_TRUE(status.ok()) << name << ": " << status.ToString();
  return request;
}

inline v1::Scene LoadScene(const std::string& name) {
  v1::Scene scene;
  const auto status =
      google::protobuf::util::JsonStringToMessage(ReadText(ExamplePath("scenes/" + name + ".json")), &scene);
  EXPECT_TRUE(status.ok()) << name << ": " << status.ToString();
  return scene;
}

/// A server on 127.0.0.1:<free port> plus a stub talking to it over loopback.
class LoopbackServer {
 public:
  explicit LoopbackServer(int threads = 2) : LoopbackServer(QuietOptions(threads)) {}
  /// A server with these options (listen is set to 127.0.0.1:0).
  explicit LoopbackServer(ServerOptions options) {
    options.listen = "127.0.0.1:0";
    server_ = std::make_unique<PlanningServer>(options);
    address_ = "127.0.0.1:" + std::to_string(server_->port());
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(options.max_message_mb << 20);  // as large as the server sends
    channel_ = grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), arguments);
    stub_ = v1::Planning::NewStub(channel_);
  }
  static ServerOptions QuietOptions(int threads) {
    ServerOptions options;
    options.threads = threads;
    options.log_requests = false;
    return options;
  }
  const std::string& address() const { return address_; }
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  PlanningServer& server() { return *server_; }
  int port() const { return server_->port(); }
  v1::Planning::Stub& stub() { return *stub_; }

  /// Plan with a generous deadline (a liveness bound only).
  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response, double deadline_s = 60.0) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::milliseconds(static_cast<int>(deadline_s * 1000)));
    return stub_->Plan(&context, request, response);
  }

  grpc::Status ListPlanners(v1::ListPlannersResponse* response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    return stub_->ListPlanners(&context, v1::ListPlannersRequest(), response);
  }

 private:
  std::unique_ptr<PlanningServer> server_;
  std::string address_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Planning::Stub> stub_;
};

/// A suite whose tests share one loopback server, started once per suite. `Base` is
/// ::testing::Test or a ::testing::TestWithParam<…>.
template <typename Base = ::testing::Test>
class SharedServerTest : public Base {
 protected:
  static void SetUpTestSuite() { server_ = new LoopbackServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  static inline LoopbackServer* server_ = nullptr;
};

}  // namespace chasles::testing
