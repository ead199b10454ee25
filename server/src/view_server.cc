#include "chasles/server/view_server.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <utility>

#include <httplib.h>

#include "chasles/robot/error.h"
#include "chasles/server/view_page.h"

namespace chasles {

void RecentExchanges::Add(Exchange exchange) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::uint64_t size = exchange.request.size() + exchange.response.size();
  if (size > max_bytes_ || max_count_ == 0) return;  // never kept: it alone is over the cap
  bytes_ += size;
  exchanges_.push_front(std::move(exchange));
  while (exchanges_.size() > max_count_ || bytes_ > max_bytes_) {
    bytes_ -= exchanges_.back().request.size() + exchanges_.back().response.size();
    exchanges_.pop_back();
  }
}

std::vector<Exchange> RecentExchanges::List() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {exchanges_.begin(), exchanges_.end()};
}

std::optional<Exchange> RecentExchanges::Find(const std::string& request_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Exchange& e : exchanges_) {
    if (e.request_id == request_id) return e;
  }
  return std::nullopt;
}

namespace {

/// The view of an exchange of these message types, by `view` (ViewOfPlan, …).
template <typename Request, typename Response, typename View>
ViewInput ViewOfExchange(const Exchange& exchange, ModelStore& store, View view) {
  Request request;
  Response response;
  if (!request.ParseFromString(exchange.request) || !response.ParseFromString(exchange.response)) {
    throw std::runtime_error(exchange.rpc + " exchange '" + exchange.request_id + "' does not parse");
  }
  return view(store, request, response);
}

}  // namespace

std::string ViewPageOf(const Exchange& exchange, ModelStore& store) {
  ViewInput view;
  if (exchange.rpc == "Plan") {
    view = ViewOfExchange<v1::PlanRequest, v1::PlanResponse>(exchange, store, ViewOfPlan);
  } else if (exchange.rpc == "Optimize") {
    view = ViewOfExchange<v1::OptimizeRequest, v1::OptimizeResponse>(exchange, store, ViewOfOptimize);
  } else if (exchange.rpc == "Coordinate") {
    view = ViewOfExchange<v1::CoordinateRequest, v1::CoordinateResponse>(exchange, store, ViewOfCoordinate);
  } else {
    throw Error(ErrorCode::kInvalidArgument, "no view for rpc " + exchange.rpc);
  }
  return ViewPageHtml(ViewDataJson(view));
}

namespace {

/// Percent-encoding of a request id for a link (ids are client text).
std::string UrlEncoded(const std::string& text) {
  std::string out;
  for (const unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      char buffer[4];
      std::snprintf(buffer, sizeof buffer, "%%%02X", c);
      out += buffer;
    }
  }
  return out;
}

}  // namespace

struct ViewServer::Impl {
  httplib::Server http;
  std::thread thread;
  int port = 0;
};

ViewServer::ViewServer(const std::string& listen, RecentExchanges* recent, ModelStore* store,
                       std::function<std::string(const std::optional<std::string>&)> authorize)
    : impl_(std::make_unique<Impl>()) {
  httplib::Server& http = impl_->http;
  http.new_task_queue = [] { return new httplib::ThreadPool(2); };  // rendering is bounded: two at a time
  // Every route: the token first (header, or ?token= for a browser), and no caching.
  const auto allowed = [authorize](const httplib::Request& request, httplib::Response& response) {
    std::optional<std::string> authorization;
    if (request.has_header("Authorization")) {
      authorization = request.get_header_value("Authorization");
    } else if (request.has_param("token")) {
      authorization = "Bearer " + request.get_param_value("token");
    }
    const std::string refusal = authorize(authorization);
    response.set_header("Cache-Control", "no-store");
    if (refusal.empty()) return true;
    response.status = 401;
    response.set_header("WWW-Authenticate", "Bearer");
    response.set_content(refusal + "\n", "text/plain; charset=utf-8");
    return false;
  };
  http.Get("/", [recent, allowed](const httplib::Request& request, httplib::Response& response) {
    if (!allowed(request, response)) return;
    const std::string token = request.has_param("token") ? "?token=" + UrlEncoded(request.get_param_value("token")) : "";
    std::string page =
        "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>chasles: recent requests</title></head><body "
        "style=\"font-family:sans-serif\"><h1>Recent requests</h1><p>The newest first; each link opens its viewer "
        "page.</p><table><tr><th>request</th><th>rpc</th><th>outcome</th><th>finished (Unix time)</th></tr>";
    for (const Exchange& e : recent->List()) {
      char when[32];
      std::snprintf(when, sizeof when, "%.3f", e.unix_time);
      page += "<tr><td><a href=\"/view/" + UrlEncoded(e.request_id) + token + "\">" + HtmlEscaped(e.request_id) +
              "</a></td><td>" + e.rpc + "</td><td>" + HtmlEscaped(e.outcome) + "</td><td>" + when + "</td></tr>";
    }
    page += "</table></body></html>";
    response.set_content(page, "text/html; charset=utf-8");
  });
  http.Get(R"(/view/([^/]+))", [recent, store, allowed](const httplib::Request& request, httplib::Response& response) {
    if (!allowed(request, response)) return;
    const std::string id = request.matches[1];
    const std::optional<Exchange> exchange = recent->Find(id);
    if (!exchange) {
      response.status = 404;
      response.set_content("no recent Plan, Optimize or Coordinate request has the id '" + id +
                               "' (the server keeps the most recent ones; see /)\n",
                           "text/plain; charset=utf-8");
      return;
    }
    try {
      response.set_content(ViewPageOf(*exchange, *store), "text/html; charset=utf-8");
    } catch (const std::exception& e) {
      response.status = 500;
      response.set_content(std::string("the view of '") + id + "' could not be drawn: " + e.what() + "\n",
                           "text/plain; charset=utf-8");
    }
  });
  const std::size_t colon = listen.rfind(':');
  if (colon == std::string::npos) throw std::runtime_error("--http-listen " + listen + " must be HOST:PORT");
  std::string host = listen.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const int port = std::stoi(listen.substr(colon + 1));
  impl_->port = port == 0 ? http.bind_to_any_port(host) : (http.bind_to_port(host, port) ? port : -1);
  if (impl_->port <= 0) throw std::runtime_error("cannot listen on " + listen + " (--http-listen)");
  impl_->thread = std::thread([this] { impl_->http.listen_after_bind(); });
}

ViewServer::~ViewServer() {
  impl_->http.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

int ViewServer::port() const { return impl_->port; }

}  // namespace chasles
