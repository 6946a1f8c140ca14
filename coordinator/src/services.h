// The coordinator's gRPC services over its state (job.proto JobService,
// worker.proto WorkerService, blob.proto BlobService; every rpc and its
// errors are documented there); internal to fabatlas_coordinator.
#pragma once

#include <grpcpp/grpcpp.h>

#include <exception>
#include <memory>
#include <string>

#include "coordinator_state.h"

namespace fabatlas::coordinator {

std::unique_ptr<grpc::Service> MakeJobService(Coordinator::Impl& impl);
std::unique_ptr<grpc::Service> MakeWorkerService(Coordinator::Impl& impl);
std::unique_ptr<grpc::Service> MakeBlobService(Coordinator::Impl& impl);

// INVALID_ARGUMENT with `message`.
grpc::Status Invalid(const std::string& message);
// The status of an exception: RESOURCE_EXHAUSTED for ResourceError,
// INVALID_ARGUMENT for InputError, else INTERNAL.
grpc::Status FromException(const std::exception& e);

}  // namespace fabatlas::coordinator
