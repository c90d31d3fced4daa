#include "bridge/bridge_camera_socket.h"

#include <sys/socket.h>

namespace vlab::bridge {

namespace {

int Granted(int fd, int option) {
  int value = 0;
  socklen_t length = sizeof(value);
  return ::getsockopt(fd, SOL_SOCKET, option, &value, &length) == 0 ? value : -1;
}

}  // namespace

int SetSocketBuffer(int fd, int option, int bytes) {
  ::setsockopt(fd, SOL_SOCKET, option, &bytes, sizeof(bytes));
  // the kernel reports twice the usable size it granted
  if (Granted(fd, option) < 2L * bytes) {
    const int force = option == SO_RCVBUF ? SO_RCVBUFFORCE : SO_SNDBUFFORCE;
    ::setsockopt(fd, SOL_SOCKET, force, &bytes, sizeof(bytes));  // fails without CAP_NET_ADMIN: fine
  }
  return Granted(fd, option);
}

}  // namespace vlab::bridge
