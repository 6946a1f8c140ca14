// BlobService (blob.proto): resumable chunked writes and reads of the
// content-addressed blob store.
#include "fabatlas/protocol/channel.h"
#include "fabatlas/v1/blob.grpc.pb.h"
#include "coordinator_state.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "services.h"

namespace fabatlas::coordinator {

namespace {

class BlobServiceImpl final : public ServiceOn<v1::BlobService::Service> {
 public:
  using ServiceOn::ServiceOn;

  Status FindMissing(ServerContext* ctx, const v1::FindMissingRequest* req, v1::FindMissingResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    for (const auto& d : req->digests())
      if (!impl_.blobs->Contains(d)) resp->add_missing_digests(d);
    return Status::OK;
  }

  Status QueryWriteStatus(ServerContext* ctx, const v1::QueryWriteStatusRequest* req,
                          v1::QueryWriteStatusResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    return Guarded([&]() -> Status {
      resp->set_committed_size(impl_.blobs->CommittedSize(req->digest()));
      // A held blob is fresh again for the collector's cutoff: the caller
      // skips the upload and goes on to name it.
      resp->set_complete(impl_.blobs->Touch(req->digest()));
      return Status::OK;
    });
  }

  Status Write(ServerContext* ctx, grpc::ServerReader<v1::WriteChunk>* reader, v1::WriteResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    v1::WriteChunk chunk;
    std::string digest;
    std::int64_t held = 0;
    try {
      while (reader->Read(&chunk)) {
        if (digest.empty()) digest = chunk.digest();
        if (chunk.digest() != digest) return Invalid("one Write stream carries one blob");
        if (chunk.data().size() > static_cast<std::size_t>(protocol::kBlobChunkBytes))
          return Invalid("chunk larger than 1 MiB");
        if (chunk.size() > (std::int64_t{4} << 30)) return Invalid("blob larger than 4 GiB");
        if (!chunk.data().empty()) held = impl_.blobs->Append(digest, chunk.offset(), chunk.data());
        if (chunk.finish()) {
          try {
            impl_.blobs->Finish(digest);
          } catch (const ResourceError& e) {
            impl_.StateWriteFailed("blob", e.what());
            return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
          } catch (const InputError& e) {
            return Status(StatusCode::DATA_LOSS, e.what());
          }
          held = impl_.blobs->Size(digest);
        }
      }
    } catch (const ResourceError& e) {
      impl_.StateWriteFailed("blob", e.what());
      return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
    } catch (const InputError& e) {
      return Status(StatusCode::FAILED_PRECONDITION, e.what());
    }
    resp->set_committed_size(held);
    resp->set_complete(!digest.empty() && impl_.blobs->Contains(digest));
    return Status::OK;
  }

  Status Read(ServerContext* ctx, const v1::ReadRequest* req, grpc::ServerWriter<v1::ReadChunk>* writer) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    std::int64_t size = impl_.blobs->Size(req->digest());
    if (size < 0) {
      // Someone needed a blob the store does not hold (collected too early,
      // or never uploaded): recorded, so a test or an operator sees it.
      impl_.Event("", "blob_missing", "read of blob " + req->digest() + ", which is not in the store");
      log::Warn("blob_missing", {{"digest", req->digest()}});
      return Status(StatusCode::NOT_FOUND, "no blob " + req->digest());
    }
    return Guarded([&]() -> Status {
      for (std::int64_t offset = req->offset(); offset < size; offset += protocol::kBlobChunkBytes) {
        v1::ReadChunk chunk;
        chunk.set_data(impl_.blobs->Read(req->digest(), offset, protocol::kBlobChunkBytes));
        if (!writer->Write(chunk)) break;
      }
      return Status::OK;
    });
  }
};

}  // namespace

std::unique_ptr<grpc::Service> MakeBlobService(Coordinator::Impl& impl) {
  return std::make_unique<BlobServiceImpl>(impl);
}

}  // namespace fabatlas::coordinator
