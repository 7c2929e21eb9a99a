// The protocol's DDS names: one vehicle's services and feed under `<vehicle>/recorder/`, and
// the vehicle names that may prefix them.
#include "auv/transfer/names.h"

#include <gtest/gtest.h>

#include <vector>

namespace auv::transfer {
namespace {

TEST(TransferNames, ServicesAndFeedArePrefixedWithTheVehicle) {
  EXPECT_EQ(listRecordingsService("sparus"), "sparus/recorder/list_recordings");
  EXPECT_EQ(fetchChunkService("sparus"), "sparus/recorder/fetch_chunk");
  EXPECT_EQ(recordingsTopic("sparus"), "sparus/recorder/recordings");
  EXPECT_LE(kDefaultMaxChunkBytes, kLargestMaxChunkBytes);
}

TEST(TransferNames, VehicleNamesAreALetterThenLettersDigitsOrUnderscores) {
  for (const std::string& good :
       std::vector<std::string>{"auv", "sparus_2", "A", std::string(64, 'v')}) {
    EXPECT_NO_THROW(checkVehicleName(good)) << good;
  }
  for (const std::string& bad :
       std::vector<std::string>{"", "2auv", "_auv", "au-v", "a/b", "a b", std::string(65, 'v')}) {
    EXPECT_THROW(checkVehicleName(bad), std::invalid_argument) << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace auv::transfer
