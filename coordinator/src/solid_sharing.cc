// Solid sharing between workers (worker.proto FetchSolid / ShareSolids; see
// coordinator_state.h).
#include <algorithm>

#include "coordinator_state.h"
#include "fabatlas/sampling/point_key_text.h"

namespace fabatlas::coordinator {

std::string Coordinator::Impl::SolidKey(const v1::SolidRef& ref) {
  return ref.job_bundle_digest() + ":" + sampling::PointKeyText({ref.point_key().begin(), ref.point_key().end()});
}

void Coordinator::Impl::ForgetShares(const std::string& bundle_digest) {
  std::lock_guard lock(share_mu);
  for (auto it = shares.lower_bound(bundle_digest + ":");
       it != shares.end() && it->first.rfind(bundle_digest + ":", 0) == 0;)
    it = shares.erase(it);
}

void Coordinator::Impl::FetchSolid(const v1::FetchSolidRequest& req, v1::FetchSolidResponse* resp,
                                   grpc::ServerContext* ctx) {
  const std::string& holder = req.holder_worker_id();
  if (holder.empty() || holder == req.worker_id()) return;
  const std::string key = SolidKey(req.solid());
  const std::int64_t wait_ms = std::clamp<std::int64_t>(req.max_wait_ms(), 0, 10000);
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
  std::unique_lock lock(share_mu);
  while (true) {
    auto it = shares.find(key);
    if (it != shares.end() && it->second.answered) {
      if (!it->second.blob.empty()) {
        // Bytes go to one caller and are not kept: the coordinator's memory
        // holds only shares not yet picked up, and a later caller's request
        // goes to the holder again.
        resp->set_blob(std::move(it->second.blob));
        shares.erase(it);
        return;
      }
      if (it->second.digest.empty()) return;
      if (blobs->Touch(it->second.digest)) {
        resp->set_digest(it->second.digest);
        return;
      }
      shares.erase(it);  // collected since: ask the holder again
      continue;
    }
    if (it == shares.end()) {
      // Ask the holder only while its ShareSolids loop is alive.
      auto polled = share_polled.find(holder);
      if (polled == share_polled.end() || polled->second < NowMs() - 3000) return;
      shares[key] = Share{.asked_ms = NowMs()};
      share_wanted[holder].push_back(req.solid());
      share_cv.notify_all();
    }
    if (stopping || ctx->IsCancelled() || std::chrono::steady_clock::now() >= until) {
      // No answer in time (holder busy, killed or gone): the next caller asks again.
      if (auto again = shares.find(key); again != shares.end() && !again->second.answered) shares.erase(again);
      return;
    }
    share_cv.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250)));
  }
}

void Coordinator::Impl::ShareSolids(const v1::ShareSolidsRequest& req, v1::ShareSolidsResponse* resp,
                                    grpc::ServerContext* ctx) {
  const std::int64_t wait_ms = std::clamp<std::int64_t>(req.max_wait_ms(), 0, 10000);
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
  std::unique_lock lock(share_mu);
  share_polled[req.worker_id()] = NowMs();
  for (const auto& shared : req.shared()) {
    Share& share = shares[SolidKey(shared.solid())];
    share.blob = shared.blob();
    share.digest = share.blob.empty() && blobs->Touch(shared.digest()) ? shared.digest() : "";
    share.answered = true;
  }
  if (req.shared_size() > 0) share_cv.notify_all();
  while (true) {
    auto& wanted = share_wanted[req.worker_id()];
    if (!wanted.empty()) {
      for (auto& ref : wanted) *resp->add_wanted() = std::move(ref);
      wanted.clear();
      break;
    }
    if (stopping || ctx->IsCancelled() || std::chrono::steady_clock::now() >= until) break;
    share_cv.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250)));
    share_polled[req.worker_id()] = NowMs();
  }
  share_polled[req.worker_id()] = NowMs();
}

}  // namespace fabatlas::coordinator
