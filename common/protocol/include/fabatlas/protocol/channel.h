// fabatlas/protocol/channel.h — transport security shared by the coordinator,
// workers and the CLI: TLS credentials from PEM files, bearer tokens,
// deadlines and keepalive (docs/protocol.md).
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

namespace fabatlas::protocol {

// Largest message either side accepts (16 MiB; blobs travel in 1 MiB chunks).
inline constexpr int kMaxMessageBytes = 16 << 20;
inline constexpr int kBlobChunkBytes = 1 << 20;

struct ClientSecurity {
  std::string token;     // bearer token sent on every call ("" = none)
  std::string tls_ca;    // PEM file of the deployment CA; "" = plaintext
  std::string tls_cert;  // optional client certificate (PEM file)
  std::string tls_key;   // its private key (PEM file)
};

// True for 127.0.0.0/8, ::1 and localhost targets or listen addresses.
bool IsLoopback(const std::string& address);

// A channel to `target` (HOST:PORT) with keepalive and bounded message sizes.
// TLS when security.tls_ca is set. Throws InputError naming an unreadable
// PEM file.
std::shared_ptr<grpc::Channel> MakeChannel(const std::string& target, const ClientSecurity& security);

// Routes gRPC's own diagnostics (e.g. "Handshake failed" on stderr) into
// the operator's log at debug level as event "grpc", so a
// refused connection is the one line its caller reports and JSON logs stay
// JSON. Idempotent; MakeChannel and the coordinator call it.
void RouteGrpcLogs();

// Holds the gRPC library until the process exits. Without it the last
// server or channel destroyed shuts gRPC down and joins an executor thread
// that can sit in a poll for up to 10 s (gRPC 1.51): `fabatlas run` ended
// 10 s after its job in about half the 10k tube jobs. Nothing is left to
// flush at exit: the store commits each change. Idempotent; MakeChannel and
// the coordinator call it, so a process that never talks gRPC never starts it.
void HoldGrpcUntilExit();

// Sets the deadline and the bearer token on a client call.
void Prepare(grpc::ClientContext& context, const ClientSecurity& security, std::chrono::milliseconds timeout);

// Server side: OK when no token is configured or the call carries
// "authorization: Bearer <token>"; otherwise UNAUTHENTICATED.
grpc::Status CheckToken(const grpc::ServerContext& context, const std::string& token);

// Reads a whole file; InputError naming it when unreadable.
std::string ReadPemFile(const std::string& path, const std::string& what);

// The bearer token stored in `path`, without trailing line breaks or spaces.
// InputError naming the file when it is unreadable or holds no token.
std::string ReadTokenFile(const std::string& path);

}  // namespace fabatlas::protocol
