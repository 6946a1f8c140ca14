// BlobService client side (see blob_transfer.h).
#include "fabatlas/protocol/blob_transfer.h"

#include <algorithm>

#include "fabatlas/sha256.h"

namespace fabatlas::protocol {

grpc::Status UploadBlob(v1::BlobService::Stub& stub, const ClientSecurity& security, const std::string& bytes,
                        std::chrono::milliseconds timeout, std::string* digest) {
  *digest = Sha256Hex(bytes);
  const auto size = static_cast<std::int64_t>(bytes.size());
  std::int64_t offset = 0;
  {
    grpc::ClientContext ctx;
    Prepare(ctx, security, timeout);
    v1::QueryWriteStatusRequest req;
    req.set_digest(*digest);
    v1::QueryWriteStatusResponse resp;
    grpc::Status s = stub.QueryWriteStatus(&ctx, req, &resp);
    if (!s.ok()) return s;
    if (resp.complete()) return grpc::Status::OK;
    offset = std::clamp<std::int64_t>(resp.committed_size(), 0, size);
  }
  grpc::ClientContext ctx;
  Prepare(ctx, security, timeout + std::chrono::milliseconds(bytes.size() / 1000));
  v1::WriteResponse resp;
  auto writer = stub.Write(&ctx, &resp);
  do {
    v1::WriteChunk chunk;
    chunk.set_digest(*digest);
    chunk.set_size(size);
    chunk.set_offset(offset);
    auto n = std::min<std::int64_t>(kBlobChunkBytes, size - offset);
    chunk.set_data(bytes.substr(static_cast<std::size_t>(offset), static_cast<std::size_t>(n)));
    offset += n;
    chunk.set_finish(offset >= size);
    if (!writer->Write(chunk)) break;
  } while (offset < size);
  writer->WritesDone();
  grpc::Status s = writer->Finish();
  if (s.ok() && !resp.complete())
    return grpc::Status(grpc::StatusCode::DATA_LOSS, "blob " + *digest + " is not complete after upload");
  return s;
}

grpc::Status DownloadBlob(v1::BlobService::Stub& stub, const ClientSecurity& security, const std::string& digest,
                          std::chrono::milliseconds timeout, std::string* bytes) {
  bytes->clear();
  grpc::ClientContext ctx;
  Prepare(ctx, security, timeout);
  v1::ReadRequest req;
  req.set_digest(digest);
  auto reader = stub.Read(&ctx, req);
  v1::ReadChunk chunk;
  while (reader->Read(&chunk)) *bytes += chunk.data();
  grpc::Status s = reader->Finish();
  if (!s.ok()) return s;
  if (Sha256Hex(*bytes) != digest)
    return grpc::Status(grpc::StatusCode::DATA_LOSS, "blob " + digest + ": downloaded bytes do not match");
  return grpc::Status::OK;
}

}  // namespace fabatlas::protocol
