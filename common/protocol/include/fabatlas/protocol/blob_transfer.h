// fabatlas/protocol/blob_transfer.h — the client side of BlobService
// (fabatlas/v1/blob.proto): resumable chunked upload and verified download,
// shared by workers and the operator's client.
#pragma once

#include <chrono>
#include <string>

#include "fabatlas/protocol/channel.h"
#include "fabatlas/v1/blob.grpc.pb.h"

namespace fabatlas::protocol {

// Uploads `bytes` as the blob named by their SHA-256 (set in *digest first,
// whatever the outcome). Asks the server what it holds (QueryWriteStatus):
// nothing to do for a finished blob, otherwise streams the rest in
// kBlobChunkBytes chunks from the committed offset (resume). The deadline is
// `timeout` plus 1 ms per kB. Returns the failing status, or OK.
grpc::Status UploadBlob(v1::BlobService::Stub& stub, const ClientSecurity& security, const std::string& bytes,
                        std::chrono::milliseconds timeout, std::string* digest);

// Reads the whole blob `digest` into *bytes and checks its SHA-256 (DATA_LOSS
// on a mismatch). Returns the failing status, or OK.
grpc::Status DownloadBlob(v1::BlobService::Stub& stub, const ClientSecurity& security, const std::string& digest,
                          std::chrono::milliseconds timeout, std::string* bytes);

}  // namespace fabatlas::protocol
