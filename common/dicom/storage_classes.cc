#include "common/dicom/storage_classes.h"

#include <dcmtk/dcmdata/dctk.h>
#include <dcmtk/dcmdata/dcuid.h>

#include "common/dicom/dataset_access.h"

namespace endorecon::dicom {

const std::vector<StorageClass>& RecordingStorageClasses() {
  static const std::vector<StorageClass> classes = [] {
    const std::vector<std::string> video = {UID_MPEG4HighProfileLevel4_1TransferSyntax,
                                            UID_MPEG4BDcompatibleHighProfileLevel4_1TransferSyntax,
                                            UID_MPEG4HighProfileLevel4_2_For2DVideoTransferSyntax,
                                            UID_MPEG4HighProfileLevel4_2_For3DVideoTransferSyntax,
                                            UID_MPEG4StereoHighProfileLevel4_2TransferSyntax,
                                            UID_MPEG2MainProfileAtMainLevelTransferSyntax,
                                            UID_MPEG2MainProfileAtHighLevelTransferSyntax,
                                            UID_HEVCMainProfileLevel5_1TransferSyntax,
                                            UID_HEVCMain10ProfileLevel5_1TransferSyntax};
    const std::vector<std::string> image = {
        UID_LittleEndianExplicitTransferSyntax, UID_LittleEndianImplicitTransferSyntax,
        UID_JPEGProcess1TransferSyntax,         UID_JPEGProcess2_4TransferSyntax,
        UID_JPEGProcess14SV1TransferSyntax,     UID_RLELosslessTransferSyntax};
    std::vector<StorageClass> all;
    for (const char* sop : {UID_VideoEndoscopicImageStorage, UID_VideoPhotographicImageStorage,
                            UID_VideoMicroscopicImageStorage}) {
      all.push_back({sop, video});
    }
    for (const char* sop :
         {UID_VLEndoscopicImageStorage, UID_VLPhotographicImageStorage, UID_SecondaryCaptureImageStorage,
          UID_MultiframeTrueColorSecondaryCaptureImageStorage,
          UID_MultiframeGrayscaleByteSecondaryCaptureImageStorage}) {
      all.push_back({sop, image});
    }
    // endorecon's own results (UID_MultiframeTrueColorSecondaryCaptureImageStorage is above).
    const std::vector<std::string> plain = {UID_LittleEndianExplicitTransferSyntax,
                                            UID_LittleEndianImplicitTransferSyntax};
    for (const char* sop :
         {UID_MultiframeGrayscaleWordSecondaryCaptureImageStorage, UID_EncapsulatedSTLStorage}) {
      all.push_back({sop, plain});
    }
    return all;
  }();
  return classes;
}

bool IsEndoreconResult(DcmItem& data) {
  const std::string sop = FindString(data, DCM_SOPClassUID).value_or("");
  const bool result_class = sop == UID_MultiframeTrueColorSecondaryCaptureImageStorage ||
                            sop == UID_MultiframeGrayscaleWordSecondaryCaptureImageStorage ||
                            sop == UID_EncapsulatedSTLStorage;
  return result_class && FindString(data, DCM_Manufacturer).value_or("") == "endorecon";
}

}  // namespace endorecon::dicom
