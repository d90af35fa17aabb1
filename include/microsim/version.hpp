// The program's version (CMakeLists.txt's project version) and the version of its record layout.
#pragma once

namespace microsim {

// "MAJOR.MINOR.PATCH", written into every record, table header and shard.
const char* version();

// Layout of the JSON records and the partial records of shards. Raised when a field changes
// meaning or is removed (fields are only ever added within one schema version).
constexpr int kRecordSchemaVersion = 1;

}  // namespace microsim
