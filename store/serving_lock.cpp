#include "store/serving_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace shadowtiles::store {

Result<ServingLock> ServingLock::acquire(const std::filesystem::path& store_dir, Kind kind) {
  const std::filesystem::path file = store_dir / kFileName;
  int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0 && errno == EACCES) fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);  // read-only copy
  if (fd < 0)
    return make_error(ErrorCode::io_error, "cannot open " + file.string() + ": " + std::strerror(errno));
  const int operation = (kind == Kind::serve ? LOCK_SH : LOCK_EX) | LOCK_NB;
  int rc;
  do rc = ::flock(fd, operation);
  while (rc != 0 && errno == EINTR);
  if (rc != 0) {
    int error = errno;
    ::close(fd);
    if (error == EWOULDBLOCK)
      return make_error(ErrorCode::invalid_input,
                        kind == Kind::serve
                            ? store_dir.string() + " is being written by a build; serve it when the build is done"
                            : store_dir.string() +
                                  " is being served; build into a new directory and point the server at it "
                                  "(see config/README.md, 'Swapping builds')");
    return make_error(ErrorCode::io_error, "cannot lock " + file.string() + ": " + std::strerror(error));
  }
  return ServingLock(fd);
}

ServingLock& ServingLock::operator=(ServingLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

ServingLock::~ServingLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the lock
}

}  // namespace shadowtiles::store
