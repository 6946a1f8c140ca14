// Channels, credentials and tokens (see channel.h).
#include "fabatlas/protocol/channel.h"

#include <grpc/grpc.h>
#include <grpc/support/log.h>

#include <fstream>
#include <mutex>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/log/log.h"

namespace fabatlas::protocol {

std::string ReadPemFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read the " + what);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

std::string ReadTokenFile(const std::string& path) {
  std::string token = ReadPemFile(path, "token file");
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ')) token.pop_back();
  if (token.empty()) throw InputError(path + ": the token file is empty");
  return token;
}

bool IsLoopback(const std::string& address) {
  std::string host = address;
  if (host.rfind("dns:", 0) == 0) host = host.substr(4);
  if (host.rfind("ipv4:", 0) == 0) host = host.substr(5);
  if (host.rfind("ipv6:", 0) == 0) host = host.substr(5);
  if (!host.empty() && host[0] == '[') {
    auto end = host.find(']');
    host = host.substr(1, end == std::string::npos ? std::string::npos : end - 1);
  } else {
    auto colon = host.rfind(':');
    if (colon != std::string::npos) host = host.substr(0, colon);
  }
  return host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

void HoldGrpcUntilExit() {
  static std::once_flag once;
  std::call_once(once, [] { grpc_init(); });  // no grpc_shutdown: see channel.h
}

void RouteGrpcLogs() {
  static std::once_flag once;
  std::call_once(once, [] {
    gpr_set_log_function([](gpr_log_func_args* args) {
      // Debug: the caller reports what failed (one line, or a log event).
      const log::Level level = log::Level::kDebug;
      if (!log::Enabled(level)) return;
      log::Write(level, "grpc",
                 {{"message", args->message ? args->message : ""},
                  {"source", std::string(args->file ? args->file : "") + ":" + std::to_string(args->line)}});
    });
  });
}

std::shared_ptr<grpc::Channel> MakeChannel(const std::string& target, const ClientSecurity& security) {
  HoldGrpcUntilExit();
  RouteGrpcLogs();
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(kMaxMessageBytes);
  args.SetMaxSendMessageSize(kMaxMessageBytes);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 20000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 5000);
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (!security.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadPemFile(security.tls_ca, "CA certificate");
    if (!security.tls_cert.empty()) {
      ssl.pem_cert_chain = ReadPemFile(security.tls_cert, "client certificate");
      ssl.pem_private_key = ReadPemFile(security.tls_key, "client key");
    }
    credentials = grpc::SslCredentials(ssl);
  } else {
    credentials = grpc::InsecureChannelCredentials();
  }
  return grpc::CreateCustomChannel(target, credentials, args);
}

void Prepare(grpc::ClientContext& context, const ClientSecurity& security, std::chrono::milliseconds timeout) {
  context.set_deadline(std::chrono::system_clock::now() + timeout);
  if (!security.token.empty()) context.AddMetadata("authorization", "Bearer " + security.token);
}

grpc::Status CheckToken(const grpc::ServerContext& context, const std::string& token) {
  if (token.empty()) return grpc::Status::OK;
  const auto& metadata = context.client_metadata();
  auto it = metadata.find("authorization");
  if (it != metadata.end() && std::string(it->second.data(), it->second.size()) == "Bearer " + token)
    return grpc::Status::OK;
  return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "missing or wrong bearer token");
}

}  // namespace fabatlas::protocol
