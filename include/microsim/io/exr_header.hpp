// A structural check of an OpenEXR file's header(s) before OpenEXR reads it: every attribute's
// declared size must fit in the file. OpenEXR 3.1 allocates a string attribute's declared size
// (up to 2 GB) before it finds that the file is shorter, so a few corrupt bytes cost gigabytes.
#pragma once
#include <string>

namespace microsim {

// UsageError naming `path` when the header is truncated or declares an attribute larger than
// the rest of the file; files that are not EXR at all are left to OpenEXR's own message.
void check_exr_header_sizes(const std::string& path);

}  // namespace microsim
