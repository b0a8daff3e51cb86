#pragma once
// A minimal WebSocket client for the bridge tests (RFC 6455 over a blocking POSIX socket):
// the handshake offering one subprotocol, masked text frames out, whole frames in. It can also
// stop reading altogether (a slow client) and shrink its receive buffer to make that bite early.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace teleop::test {

struct WsFrame {
  std::uint8_t opcode = 0;  ///< 1 text, 2 binary, 8 close
  std::vector<std::uint8_t> payload;
  std::string text() const { return std::string(payload.begin(), payload.end()); }
};

class WsClient {
 public:
  /// Connects to 127.0.0.1:port and completes the handshake; ok() says whether it did.
  /// `rcvbuf` > 0 sets SO_RCVBUF before connecting.
  WsClient(int port, const std::string& subprotocol, int rcvbuf = 0) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    if (rcvbuf > 0) setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof(rcvbuf));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) != 0) return;
    const std::string req = "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                            "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                            "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                            "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: " +
                            subprotocol + "\r\n\r\n";
    if (!write_all(req.data(), req.size())) return;
    while (response_.find("\r\n\r\n") == std::string::npos) {
      char c;
      if (!read_all(&c, 1, 5000)) return;
      response_ += c;
    }
    ok_ = response_.compare(0, 12, "HTTP/1.1 101") == 0;
  }
  ~WsClient() {
    if (fd_ >= 0) close(fd_);
  }
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  bool ok() const { return ok_; }
  const std::string& response() const { return response_; }

  /// Sends a masked frame (mask 0: the bytes travel as they are).
  bool send(const std::string& payload, std::uint8_t opcode = 1) {
    std::vector<std::uint8_t> f{static_cast<std::uint8_t>(0x80 | opcode)};
    const std::size_t n = payload.size();
    if (n < 126) {
      f.push_back(static_cast<std::uint8_t>(0x80 | n));
    } else {
      f.push_back(0x80 | 126);
      f.push_back(static_cast<std::uint8_t>(n >> 8));
      f.push_back(static_cast<std::uint8_t>(n));
    }
    f.insert(f.end(), {0, 0, 0, 0});
    f.insert(f.end(), payload.begin(), payload.end());
    return write_all(f.data(), f.size());
  }

  /// The next whole frame, or nothing within timeout_ms.
  std::optional<WsFrame> read(int timeout_ms) {
    std::uint8_t h[2];
    if (!read_all(h, 2, timeout_ms)) return std::nullopt;
    WsFrame f;
    f.opcode = h[0] & 0x0f;
    std::uint64_t n = h[1] & 0x7f;
    if (n == 126 || n == 127) {
      std::uint8_t e[8];
      const int k = n == 126 ? 2 : 8;
      if (!read_all(e, static_cast<std::size_t>(k), timeout_ms)) return std::nullopt;
      n = 0;
      for (int i = 0; i < k; ++i) n = (n << 8) | e[i];
    }
    if (n > (64u << 20)) return std::nullopt;
    f.payload.resize(n);
    if (n > 0 && !read_all(f.payload.data(), n, timeout_ms)) return std::nullopt;
    return f;
  }

 private:
  bool write_all(const void* p, std::size_t n) {
    const auto* b = static_cast<const char*>(p);
    while (n > 0) {
      const ssize_t w = ::send(fd_, b, n, MSG_NOSIGNAL);
      if (w <= 0) return false;
      b += w;
      n -= static_cast<std::size_t>(w);
    }
    return true;
  }
  bool read_all(void* p, std::size_t n, int timeout_ms) {
    auto* b = static_cast<char*>(p);
    while (n > 0) {
      pollfd pf{fd_, POLLIN, 0};
      if (poll(&pf, 1, timeout_ms) <= 0) return false;
      const ssize_t r = ::recv(fd_, b, n, 0);
      if (r <= 0) return false;
      b += r;
      n -= static_cast<std::size_t>(r);
    }
    return true;
  }
  int fd_ = -1;
  bool ok_ = false;
  std::string response_;
};

}  // namespace teleop::test
