#pragma once
// A real redis-server (Debian's /usr/bin/redis-server) on 127.0.0.1:<free port> with its own
// directory and append-only file, started and stopped by the test: bounded (it answers PING
// within 10 s or the test fails), killed and reaped on destruction.

#include <fcntl.h>
#include <netinet/in.h>
#include <sys/prctl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

#include "chasles/server/redis_client.h"

namespace chasles::testing {

/// A free TCP port on 127.0.0.1 (bound and released; good enough for a test).
inline int FreeLoopbackPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
  socklen_t length = sizeof(address);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  const int port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

class RedisServer {
 public:
  RedisServer() : port_(FreeLoopbackPort()) {
    char pattern[] = "/tmp/chasles-redis-XXXXXX";
    if (::mkdtemp(pattern) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = pattern;
    Start();
  }
  ~RedisServer() {
    Stop();
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  RedisServer(const RedisServer&) = delete;
  RedisServer& operator=(const RedisServer&) = delete;

  std::string url() const { return "redis://127.0.0.1:" + std::to_string(port_); }
  int port() const { return port_; }

  /// Starts redis-server on the same port and directory (its append-only file is read back).
  void Start() {
    pid_ = ::fork();
    if (pid_ == 0) {
      // Not the test's stdout/stderr (ctest waits for every holder of its pipes to close them),
      // and gone with the test however it ends.
      const int null = ::open("/dev/null", O_RDWR);
      ::dup2(null, STDIN_FILENO);
      ::dup2(null, STDOUT_FILENO);
      ::dup2(null, STDERR_FILENO);
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      const std::string port = std::to_string(port_);
      const std::string log = dir_ + "/redis.log";
      ::execl("/usr/bin/redis-server", "redis-server", "--port", port.c_str(), "--bind", "127.0.0.1", "--dir",
              dir_.c_str(), "--appendonly", "yes", "--appendfsync", "always", "--save", "", "--daemonize", "no",
              "--loglevel", "warning", "--logfile", log.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (std::chrono::steady_clock::now() < until) {
      try {
        RedisAddress address;
        address.port = port_;
        RedisClient probe(address, 0.5);
        return;
      } catch (...) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
    Stop();
    throw std::runtime_error("redis-server did not answer on port " + std::to_string(port_) + " within 10 s");
  }

  /// SIGKILL, reaped: Redis gets no chance to flush anything (with appendfsync always every
  /// acknowledged write is on disk already).
  void Kill() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }

  /// SIGTERM (Redis flushes its append-only file and exits), reaped; SIGKILL after 10 s.
  void Stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    int status = 0;
    while (::waitpid(pid_, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > until) {
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    pid_ = -1;
  }

 private:
  int port_;
  std::string dir_;
  pid_t pid_ = -1;
};

}  // namespace chasles::testing
