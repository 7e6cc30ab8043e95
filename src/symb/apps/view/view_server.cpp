#include "symb/apps/view/view_server.hpp"

#include <civetweb.h>

#include <algorithm>
#include <cstring>
#include <thread>

#include "symb/apps/view/web_assets.hpp"
#include "symb/io/tcp_stream.hpp"
#include "symb/shell/shell_task.hpp"
#include "symb/shell/tcp_shell.hpp"

namespace symb::apps::view {

namespace {

using namespace std::chrono_literals;

constexpr kernel::Duration kPollEvery = 20ms;  // how often an idle sender asks poll()
// How long the stop waits for the senders to finish the frame they are writing and say goodbye:
// civetweb refuses every write once it is told to stop, so a frame still going out then is cut.
constexpr kernel::Duration kGoodbyeWait = 2s;
constexpr std::size_t kMaxTokenBytes = 256;

// The token of a request's query string ("token=..."), or empty.
std::string query_token(const mg_connection* conn) {
  const mg_request_info* info = mg_get_request_info(conn);
  if (!info || !info->query_string) return {};
  char buf[kMaxTokenBytes + 1];
  const int n = mg_get_var(info->query_string, std::strlen(info->query_string), "token", buf, sizeof buf);
  return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
}

}  // namespace

const WebAsset* find_web_asset(std::string_view path) {
  if (path == "/") path = "/index.html";
  for (const WebAsset& a : web_assets())
    if (a.path == path) return &a;
  return nullptr;
}

// One browser. The civetweb thread of its connection and its sender thread both touch it.
struct ViewServer::Client {
  explicit Client(std::size_t capacity) : queue(capacity) {}
  ClientId id = 0;
  mg_connection* conn = nullptr;
  FrameQueue queue;
  std::thread sender;
  std::atomic<bool> open{true};
  std::atomic<bool> farewell{false};  // the server is going: say goodbye so the client closes
  std::atomic<bool> ended{false};     // the sender has left its loop (and said goodbye if asked)
};

kernel::Result<std::unique_ptr<ViewServer>> ViewServer::start(ViewServerOptions options, ViewServerHandlers handlers) {
  if (options.max_clients == 0 || options.queue_frames == 0)
    return kernel::Error{"view: max_clients and queue_frames must be at least 1"};
  if (options.token.empty()) {
    auto t = shell::random_token();
    if (!t) return kernel::Error{"view: " + t.error()};
    options.token = *t;
  }
  if (options.token.size() > kMaxTokenBytes) return kernel::Error{"view: the token is longer than 256 bytes"};
  if (options.host.find_first_of(",: ") != std::string::npos && options.host.front() != '[')
    return kernel::Error{"view: bad address '" + options.host + "'"};
  auto server = std::unique_ptr<ViewServer>(new ViewServer(std::move(options), std::move(handlers)));
  const std::string ports = server->options_.host + ":" + std::to_string(server->options_.port);
  // A WebSocket holds one of civetweb's worker threads while it is open; two more serve pages.
  const std::string threads = std::to_string(server->options_.max_clients + 2);
  const char* mg_options[] = {"listening_ports",
                              ports.c_str(),
                              "num_threads",
                              threads.c_str(),
                              "request_timeout_ms",
                              "10000",
                              "websocket_timeout_ms",
                              "3600000",
                              "enable_keep_alive",
                              "no",

                              nullptr};
  mg_callbacks callbacks{};
  callbacks.log_message = [](const mg_connection*, const char*) { return 1; };  // errors come back as results
  server->ctx_ = mg_start(&callbacks, server.get(), mg_options);
  if (!server->ctx_) return kernel::Error{"view: cannot listen on " + ports + " (in use, or not an address here)"};
  mg_server_port port{};
  if (mg_get_server_ports(server->ctx_, 1, &port) < 1 || port.port <= 0)
    return kernel::Error{"view: cannot tell which port " + ports + " got"};
  server->port_ = static_cast<std::uint16_t>(port.port);
  mg_set_request_handler(server->ctx_, "/", &ViewServer::on_request, server.get());
  mg_set_websocket_handler(server->ctx_, "/ws", &ViewServer::on_ws_connect, &ViewServer::on_ws_ready,
                           &ViewServer::on_ws_data, &ViewServer::on_ws_close, server.get());
  return server;
}

ViewServer::ViewServer(ViewServerOptions options, ViewServerHandlers handlers)
    : options_(std::move(options)), handlers_(std::move(handlers)) {}

ViewServer::~ViewServer() {
  std::vector<std::shared_ptr<Client>> clients;
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
    clients = clients_;
  }
  // The senders first: each finishes the frame it is writing and says goodbye (a WebSocket
  // close), so that a browser has every frame flush() saw go out and closes its end, and
  // civetweb's thread reading it stops at once rather than at its next 2 s poll. Only then is
  // civetweb stopped: from that moment it writes nothing more.
  for (auto& c : clients) {
    c->farewell = true;
    c->queue.close();
  }
  const auto until = std::chrono::steady_clock::now() + kGoodbyeWait;
  for (auto& c : clients)
    while (!c->ended.load() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(1ms);
  if (ctx_) {
    // civetweb's listening thread sees the stop only when its poll() returns, which it does every
    // 2 s when nothing happens: a connection made meanwhile wakes it at once.
    std::atomic<bool> stopped{false};
    std::thread waker([this, &stopped] {
      while (!stopped.load()) {
        std::this_thread::sleep_for(5ms);
        if (auto conn = io::TcpStream::connect(options_.host == "0.0.0.0" ? "127.0.0.1" : options_.host, port_, 100ms))
          (*conn)->close();
      }
    });
    mg_stop(ctx_);  // calls on_ws_close for each open WebSocket, which joins its sender
    stopped = true;
    waker.join();
  }
  for (auto& c : clients)
    if (c->sender.joinable()) c->sender.join();
}

std::string ViewServer::url() const {
  return "http://" + options_.host + ":" + std::to_string(port_) + "/?token=" + options_.token;
}

int ViewServer::on_request(mg_connection* conn, void* self) {
  (void)self;
  const mg_request_info* info = mg_get_request_info(conn);
  const WebAsset* asset = info && info->local_uri ? find_web_asset(info->local_uri) : nullptr;
  if (!asset) {
    mg_send_http_error(conn, 404, "%s", "not found");
    return 404;
  }
  mg_printf(conn,
            "HTTP/1.1 200 OK\r\nContent-Type: %.*s\r\nContent-Length: %zu\r\nCache-Control: no-store\r\n"
            "Connection: close\r\n\r\n",
            static_cast<int>(asset->mime.size()), asset->mime.data(), asset->body.size());
  mg_write(conn, asset->body.data(), asset->body.size());
  return 200;
}

int ViewServer::on_ws_connect(const mg_connection* conn, void* self) {
  auto* s = static_cast<ViewServer*>(self);
  std::lock_guard lock(s->mu_);
  if (!shell::same_token(query_token(conn), s->options_.token) || s->clients_.size() >= s->options_.max_clients) {
    ++s->stats_.refused;
    // Said before civetweb closes the connection: the upgrade is answered, not just dropped.
    static constexpr char kRefusal[] =
        "HTTP/1.1 403 Forbidden\r\nContent-Type: text/plain\r\nContent-Length: 32\r\nConnection: close\r\n\r\n"
        "wrong token or too many viewers\n";
    mg_write(const_cast<mg_connection*>(conn), kRefusal, sizeof kRefusal - 1);
    return 1;
  }
  return 0;
}

void ViewServer::on_ws_ready(mg_connection* conn, void* self) {
  auto* s = static_cast<ViewServer*>(self);
  auto client = std::make_shared<Client>(s->options_.queue_frames);
  client->conn = conn;
  {
    std::lock_guard lock(s->mu_);
    client->id = s->next_id_++;
    ++s->stats_.clients_opened;
    s->clients_.push_back(client);
    // Upgraded while the server stops (the destructor has already told the others goodbye).
    if (s->stopping_) {
      client->farewell = true;
      client->queue.close();
    }
  }
  mg_set_user_connection_data(conn, client.get());
  s->clients_live_.fetch_add(1, std::memory_order_relaxed);
  if (s->handlers_.on_open) s->handlers_.on_open(client->id);
  client->sender = std::thread([s, client] { s->send_loop(client); });
}

int ViewServer::on_ws_data(mg_connection* conn, int bits, char* data, std::size_t len, void* self) {
  auto* s = static_cast<ViewServer*>(self);
  auto* client = static_cast<Client*>(mg_get_user_connection_data(conn));
  const int opcode = bits & 0x0f;
  if (opcode == MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE) return 0;
  if (client && opcode == MG_WEBSOCKET_OPCODE_TEXT && s->handlers_.on_message)
    s->handlers_.on_message(client->id, std::string_view(data, len));
  return 1;
}

void ViewServer::on_ws_close(const mg_connection* conn, void* self) {
  auto* s = static_cast<ViewServer*>(self);
  auto* raw = static_cast<Client*>(mg_get_user_connection_data(conn));
  std::shared_ptr<Client> client;
  {
    std::lock_guard lock(s->mu_);
    const auto it = std::find_if(s->clients_.begin(), s->clients_.end(), [&](auto& c) { return c.get() == raw; });
    if (it == s->clients_.end()) return;
    client = *it;
  }
  s->retire(client);
}

void ViewServer::retire(const std::shared_ptr<Client>& client) {
  client->open = false;
  client->queue.close();
  if (client->sender.joinable() && client->sender.get_id() != std::this_thread::get_id()) client->sender.join();
  {
    std::lock_guard lock(mu_);
    const FrameQueueStats q = client->queue.stats();
    stats_.frames.pushed += q.pushed;
    stats_.frames.sent += q.sent;
    stats_.frames.dropped += q.dropped;
    std::erase(clients_, client);
  }
  clients_live_.fetch_sub(1, std::memory_order_relaxed);
  if (handlers_.on_close) handlers_.on_close(client->id);
}

void ViewServer::send_loop(const std::shared_ptr<Client>& client) {
  struct Ended {
    Client& c;
    ~Ended() { c.ended = true; }
  } ended{*client};
  while (client->open.load()) {
    std::optional<std::string> frame = client->queue.pop(kPollEvery);
    if (!frame && client->queue.closed()) break;
    const bool queued = frame.has_value();
    if (!frame && handlers_.poll) frame = handlers_.poll(client->id);
    if (!frame) continue;
    const bool written = mg_websocket_write(client->conn, MG_WEBSOCKET_OPCODE_TEXT, frame->data(), frame->size()) > 0;
    if (queued) client->queue.done(written);
    if (!written) {
      // The client is gone or timed out: stop sending; civetweb closes the connection.
      client->queue.close();
      return;
    }
  }
  if (client->farewell.load()) {
    static constexpr char kGoingAway[] = {'\x03', '\xe9'};  // status 1001: the server is going away
    mg_websocket_write(client->conn, MG_WEBSOCKET_OPCODE_CONNECTION_CLOSE, kGoingAway, sizeof kGoingAway);
  }
}

void ViewServer::send(ClientId id, std::string frame) {
  std::shared_ptr<Client> client;
  {
    std::lock_guard lock(mu_);
    for (auto& c : clients_)
      if (c->id == id) client = c;
  }
  if (client) client->queue.push(std::move(frame));
}

void ViewServer::broadcast(const std::string& frame) {
  std::vector<std::shared_ptr<Client>> clients;
  {
    std::lock_guard lock(mu_);
    clients = clients_;
  }
  for (auto& c : clients) c->queue.push(frame);
}

bool ViewServer::flush(kernel::Duration stall, kernel::Duration limit) const {
  // Progress, not a fixed moment: a client reading as fast as a busy machine lets it can take
  // longer than any fixed wait, and one that reads nothing should not hold the run's end for long.
  const auto started = std::chrono::steady_clock::now();
  auto progress = started;
  FrameQueueStats frames = stats().frames;
  while (frames.queued > 0) {
    const auto now = std::chrono::steady_clock::now();
    if (now - progress >= stall || now - started >= limit) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const FrameQueueStats next = stats().frames;
    if (next.sent != frames.sent) progress = std::chrono::steady_clock::now();
    frames = next;
  }
  return true;
}

ViewServerStats ViewServer::stats() const {
  std::lock_guard lock(mu_);
  ViewServerStats s = stats_;
  for (auto& c : clients_) {
    const FrameQueueStats q = c->queue.stats();
    s.frames.pushed += q.pushed;
    s.frames.sent += q.sent;
    s.frames.dropped += q.dropped;
    s.frames.queued += q.queued;
  }
  return s;
}

}  // namespace symb::apps::view
