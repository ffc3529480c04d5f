// SPDX-License-Identifier: Apache-2.0
// termios2 lives in the kernel headers, which clash with glibc's <termios.h>: this file
// includes only the former.
#include <asm/ioctls.h>
#include <asm/termbits.h>

#include <cstdint>

#include "swivel/dynamixel/serial_port.hpp"

extern "C" int ioctl(int fd, unsigned long request, ...);  // NOLINT: <sys/ioctl.h> clashes

namespace swivel::dynamixel {

bool set_custom_baud(int fd, std::uint32_t baud) noexcept {
  struct termios2 tio {};
  if (ioctl(fd, TCGETS2, &tio) != 0) return false;
  tio.c_cflag &= ~static_cast<tcflag_t>(CBAUD);
  tio.c_cflag |= BOTHER;
  tio.c_ispeed = baud;
  tio.c_ospeed = baud;
  return ioctl(fd, TCSETS2, &tio) == 0;
}

std::uint32_t get_baud(int fd) noexcept {
  struct termios2 tio {};
  if (ioctl(fd, TCGETS2, &tio) != 0) return 0;
  return tio.c_ospeed;
}

}  // namespace swivel::dynamixel
