#include "common/dicom/file_save.h"

#include <dcmtk/dcmdata/dcostrmb.h>

#include <string>
#include <system_error>
#include <vector>

#include "common/error.h"
#include "common/file_write.h"

namespace endorecon::dicom {

void SaveFile(DcmFileFormat& file, const std::filesystem::path& path, E_TransferSyntax xfer) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    FailInvalid(path.string() + ": not a regular file; name a file to write the DICOM instance to");
  // DCMTK's own file stream drops write errors; its buffer stream hands the encoded bytes over a block
  // at a time, as its network code does.
  std::vector<char> block(1 << 20);
  DcmOutputBufferStream stream(block.data(), block.size());
  std::string bytes;
  const auto take = [&] {
    void* data = nullptr;
    offile_off_t length = 0;
    stream.flushBuffer(data, length);
    bytes.append(static_cast<const char*>(data), static_cast<std::size_t>(length));
  };
  file.transferInit();
  OFCondition written = EC_StreamNotifyClient;
  while (written == EC_StreamNotifyClient) {
    written = file.write(stream, xfer, EET_UndefinedLength, nullptr);  // as saveFile's default
    take();
  }
  file.transferEnd();
  if (written.bad()) Fail(ErrorCode::kInternal, "cannot encode " + path.string() + ": " + written.text());
  WriteFile(path, bytes, "DICOM instance");
}

}  // namespace endorecon::dicom
