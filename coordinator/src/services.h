// The coordinator's gRPC services over its state (job.proto JobService,
// worker.proto WorkerService, blob.proto BlobService; every rpc and its
// errors are documented there); internal to fabatlas_coordinator.
#pragma once

#include <grpcpp/grpcpp.h>

#include <exception>
#include <functional>
#include <memory>
#include <string>

#include "coordinator_state.h"
#include "fabatlas/error.h"
#include "fabatlas/protocol/channel.h"

namespace fabatlas::coordinator {

using grpc::ServerContext;
using grpc::Status;
using grpc::StatusCode;

std::unique_ptr<grpc::Service> MakeJobService(Coordinator::Impl& impl);
std::unique_ptr<grpc::Service> MakeWorkerService(Coordinator::Impl& impl);
std::unique_ptr<grpc::Service> MakeBlobService(Coordinator::Impl& impl);

// INVALID_ARGUMENT with `message`.
grpc::Status Invalid(const std::string& message);
// The status of an exception: RESOURCE_EXHAUSTED for ResourceError,
// INVALID_ARGUMENT for InputError, else INTERNAL.
grpc::Status FromException(const std::exception& e);

// What every service shares: the coordinator's state (impl_) and the token
// check each rpc makes first (protocol::CheckToken against --token:
// UNAUTHENTICATED without it).
template <class GrpcService>
class ServiceOn : public GrpcService {
 public:
  explicit ServiceOn(Coordinator::Impl& impl) : impl_(impl) {}

 protected:
  grpc::Status Authorise(const grpc::ServerContext& context) const {
    return protocol::CheckToken(context, impl_.options.token);
  }

  Coordinator::Impl& impl_;
};

// Runs `body` (returns a grpc::Status); an exception it throws becomes
// FromException's status, after on_resource(e) for a ResourceError.
template <class Body>
grpc::Status Guarded(Body&& body, const std::function<void(const ResourceError&)>& on_resource = {}) {
  try {
    return body();
  } catch (const ResourceError& e) {
    if (on_resource) on_resource(e);
    return FromException(e);
  } catch (const std::exception& e) {
    return FromException(e);
  }
}

}  // namespace fabatlas::coordinator
