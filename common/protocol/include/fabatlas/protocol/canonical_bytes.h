// fabatlas/protocol/canonical_bytes.h — a message's canonical bytes: protobuf
// deterministic serialization (map entries in key order), so equal messages
// give equal bytes within one build of the protocol (what job bundles and
// cache-plan reports are digested and compared by).
#pragma once

#include <google/protobuf/message_lite.h>

#include <string>

namespace fabatlas::protocol {

std::string CanonicalBytes(const google::protobuf::MessageLite& message);

}  // namespace fabatlas::protocol
