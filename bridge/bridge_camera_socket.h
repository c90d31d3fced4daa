// Socket buffer sizes for camera streams. A raw 640x480 frame is 16 chunks of
// 60 kB sent back to back; Linux's default receive buffer (208 KiB) holds
// about three of them, so camera sockets ask for more.
#pragma once

namespace vlab::bridge {

/// Asks for a `bytes`-byte buffer (option SO_RCVBUF or SO_SNDBUF) on socket
/// `fd`: first within the system limit (net.core.rmem_max / wmem_max), then,
/// if the kernel granted less and the process may (CAP_NET_ADMIN), with
/// SO_RCVBUFFORCE / SO_SNDBUFFORCE. Returns the size the kernel reports
/// (Linux doubles the request to account for its bookkeeping), or -1.
int SetSocketBuffer(int fd, int option, int bytes);

}  // namespace vlab::bridge
