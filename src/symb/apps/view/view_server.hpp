// ViewServer: the web view's HTTP and WebSocket server (`symb run --view`), on civetweb (Debian
// libcivetweb-dev). It serves the page's static files (embedded in the binary: web_assets.hpp)
// and, at /ws, a WebSocket per browser over which the run sends JSON frames and the page sends
// one-line commands. It listens on 127.0.0.1 unless told otherwise; a WebSocket needs the token
// (`/ws?token=T`): a random one made as the TCP shell makes its own (shell::random_token) and
// compared as the shell compares its own (shell::same_token). A wrong token is refused with 403.
//
// The run never waits for a browser: send() and broadcast() put a frame in each client's bounded
// FrameQueue (the oldest frame goes when it is full, counted), and a sender thread per client
// drains it into mg_websocket_write, which blocks while the client does not read. A stalled
// client thus costs its own thread, never the run.
//
// Handlers are called on civetweb's threads (one per connection); the server must be destroyed
// before what they touch.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "symb/apps/view/frame_queue.hpp"
#include "symb/kernel/result.hpp"

struct mg_context;
struct mg_connection;

namespace symb::apps::view {

using ClientId = std::uint64_t;

struct ViewServerOptions {
  std::string host = "127.0.0.1";
  std::uint16_t port = 0;  // 0: a free port, see port()
  std::string token;       // empty: a random one
  std::size_t max_clients = 4;
  std::size_t queue_frames = 64;  // per client
};

struct ViewServerHandlers {
  // A client's WebSocket is open: send it what it needs first (send() works from here).
  std::function<void(ClientId)> on_open;
  // One text message from the page.
  std::function<void(ClientId, std::string_view)> on_message;
  // The client is gone (after its last on_message).
  std::function<void(ClientId)> on_close;
  // Asked by the client's sender thread when its queue is idle (every 20 ms at most): a frame to
  // send now, if any (a shell's output). May be empty.
  std::function<std::optional<std::string>(ClientId)> poll;
};

struct ViewServerStats {
  std::uint64_t clients_opened = 0;
  std::uint64_t refused = 0;  // wrong token, too many clients
  FrameQueueStats frames;     // summed over every client, closed ones included
};

class ViewServer {
 public:
  static kernel::Result<std::unique_ptr<ViewServer>> start(ViewServerOptions options, ViewServerHandlers handlers);
  // Says goodbye to every client (a WebSocket close, after the frames being written), then stops
  // listening and joins the sender threads.
  ~ViewServer();
  ViewServer(const ViewServer&) = delete;
  ViewServer& operator=(const ViewServer&) = delete;

  const std::string& host() const { return options_.host; }
  std::uint16_t port() const { return port_; }
  const std::string& token() const { return options_.token; }
  // What a person opens: http://HOST:PORT/?token=T
  std::string url() const;

  // Queues `frame` for one client (nothing when it is gone) or for every client.
  void send(ClientId client, std::string frame);
  void broadcast(const std::string& frame);
  // Clients connected now; cheap enough to ask at every step.
  std::size_t client_count() const { return clients_live_.load(std::memory_order_relaxed); }
  ViewServerStats stats() const;
  // Waits while frames are queued for the clients and they keep taking them: gives up once none
  // was taken for `stall` (a stalled client) or after `limit` in all. Returns whether every frame
  // queued went out. For the end of a run, whose last frames say that it is over.
  bool flush(kernel::Duration stall, kernel::Duration limit) const;

 private:
  struct Client;
  ViewServer(ViewServerOptions options, ViewServerHandlers handlers);

  static int on_request(mg_connection* conn, void* self);
  static int on_ws_connect(const mg_connection* conn, void* self);
  static void on_ws_ready(mg_connection* conn, void* self);
  static int on_ws_data(mg_connection* conn, int bits, char* data, std::size_t len, void* self);
  static void on_ws_close(const mg_connection* conn, void* self);
  void send_loop(const std::shared_ptr<Client>& client);
  void retire(const std::shared_ptr<Client>& client);

  ViewServerOptions options_;
  ViewServerHandlers handlers_;
  mg_context* ctx_ = nullptr;
  std::uint16_t port_ = 0;
  std::atomic<std::size_t> clients_live_{0};
  mutable std::mutex mu_;  // clients_, stats_, next_id_, stopping_
  std::vector<std::shared_ptr<Client>> clients_;
  bool stopping_ = false;  // the destructor has begun: a client upgraded now is told goodbye at once
  ViewServerStats stats_;
  ClientId next_id_ = 1;
};

}  // namespace symb::apps::view
