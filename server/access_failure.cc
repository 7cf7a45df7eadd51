#include "server/access_failure.h"

#include <cerrno>
#include <cstring>

#include "common/error.h"

namespace endorecon::server {

void FailAccess(const std::string& what, int error) {
  const bool permission = error == EACCES || error == EPERM || error == EROFS;
  Fail(permission ? ErrorCode::kFailedPrecondition : ErrorCode::kUnavailable,
       what + ": " + std::strerror(error) +
           (permission ? " (owned by another user? chown it, or the data folder with -R, to the server's user)"
                       : ""));
}

}  // namespace endorecon::server
