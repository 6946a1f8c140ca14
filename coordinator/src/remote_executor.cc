// Task batches through the store to the workers, and the pipeline's
// executor on the cluster (see remote_executor.h, coordinator_state.h).
#include "remote_executor.h"

#include <algorithm>

#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "store_subtrees.h"

namespace fabatlas::coordinator {

std::vector<std::vector<std::string>> SampleBatchAffinity(std::size_t tasks,
                                                          const std::vector<std::pair<std::string, int>>& workers) {
  std::vector<std::vector<std::string>> preferred(tasks);
  if (workers.size() < 2) return preferred;
  std::size_t total = 0;
  for (const auto& w : workers) total += static_cast<std::size_t>(w.second);
  std::size_t begin = 0, slots_before = 0;
  for (const auto& [id, slots] : workers) {
    slots_before += static_cast<std::size_t>(slots);
    std::size_t end = tasks * slots_before / total;
    for (std::size_t i = begin; i < end; ++i) preferred[i] = {id};
    begin = end;
  }
  return preferred;
}

void Coordinator::Impl::Deliver(const std::vector<Delivery>& results, const std::string& worker) {
  bool complete = false;
  std::map<std::string, EtaProgress> work;  // job -> fresh work delivered now
  {
    std::lock_guard lock(results_mu);
    for (const Delivery& d : results) {
      auto range = waiting.equal_range(*d.key);
      bool counted = false;
      for (auto it = range.first; it != range.second; ++it)
        if (it->second->results.emplace(*d.key, *d.result).second) {
          it->second->workers.emplace(*d.key, worker);
          if (--it->second->pending == 0) complete = true;
          if (d.cpu_seconds >= 0 && !counted) {
            EtaProgress& w = work[it->second->job_id];
            w.cpu_seconds += d.cpu_seconds;
            w.tasks += 1;
            counted = true;
          }
        }
    }
  }
  if (complete) results_cv.notify_all();
  if (work.empty()) return;
  // The ETA's rate (job_eta.h): the job's running totals over the last window.
  const auto now = std::chrono::steady_clock::now();
  const auto window = std::chrono::duration<double>(JobEtaOptions{}.rate_window_seconds);
  std::lock_guard lock(schedule_mu);
  for (const auto& [job, w] : work) {
    auto it = schedules.find(job);
    if (it == schedules.end()) continue;
    Schedule& sch = it->second;
    sch.work.cpu_seconds += w.cpu_seconds;
    sch.work.tasks += w.tasks;
    sch.work_history.emplace_back(now, sch.work);
    while (sch.work_history.size() > 2 && now - sch.work_history[1].first >= window) sch.work_history.pop_front();
  }
}

std::vector<std::string> Coordinator::Impl::RunTasks(const std::string& job_id,
                                                     const std::vector<std::string>& payloads,
                                                     const std::vector<std::string>& keys,
                                                     const std::vector<int>& kinds,
                                                     const std::vector<std::vector<std::string>>& preferred,
                                                     std::vector<std::string>* workers_out) {
  Waiter waiter;
  waiter.job_id = job_id;
  std::vector<storage::NewTask> tasks;
  std::set<std::string> unique;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (unique.insert(keys[i]).second) {
      tasks.push_back({keys[i], job_id, kinds[i], payloads[i], {}});
      if (options.lease_affinity && i < preferred.size()) tasks.back().preferred_workers = preferred[i];
    }
  {
    std::lock_guard lock(results_mu);
    waiter.pending = unique.size();
    for (const auto& key : unique) waiting.emplace(key, &waiter);
  }
  auto unregister = [&] {
    for (const auto& key : unique) {
      auto range = waiting.equal_range(key);
      for (auto it = range.first; it != range.second; ++it)
        if (it->second == &waiter) {
          waiting.erase(it);
          break;
        }
    }
  };
  std::map<std::string, std::string> finished;
  try {
    finished = store->AddTasks(tasks);
  } catch (...) {
    std::lock_guard lock(results_mu);
    unregister();
    throw;
  }
  log::Info("round_started", {{"job", job_id},
                              {"kind", kinds.empty() ? "" : protocol::TaskKindName(kinds[0])},
                              {"tasks", tasks.size()},
                              {"stored", finished.size()}});
  std::vector<Delivery> stored;
  for (const auto& [key, result] : finished) stored.push_back({&key, &result});
  Deliver(stored);
  SignalWork();
  std::unique_lock lock(results_mu);
  results_cv.wait(lock, [&] { return waiter.pending == 0 || stopping || cancelled_jobs.count(job_id) > 0; });
  unregister();
  if (waiter.pending > 0) {
    if (stopping) throw Stopping{};
    throw JobCancelled{};
  }
  std::vector<std::string> out;
  out.reserve(keys.size());
  for (const auto& key : keys) out.push_back(waiter.results.at(key));
  if (workers_out) {
    workers_out->clear();
    for (const auto& key : keys) workers_out->push_back(waiter.workers[key]);
  }
  return out;
}

std::vector<sampling::SampleOutcome> RemoteExecutor::RunSampleTasks(const std::vector<sampling::SampleTask>& tasks,
                                                                    sampling::SampleEvaluator&,
                                                                    std::vector<sampling::TaskTiming>* timings) {
  std::vector<v1::TaskPayload> payloads;
  for (const auto& t : tasks) payloads.push_back(protocol::SamplePayload(t));
  const std::vector<std::vector<std::string>> preferred = SampleBatchAffinity(tasks.size(), impl_.ConnectedWorkers());
  std::vector<std::string> producers;
  if (!tasks.empty()) dims_ = tasks[0].point.key.size();
  BeginBatch(/*samples=*/true, tasks.size());
  auto results = Run(payloads, preferred, &producers);
  EndBatch(results);
  std::vector<sampling::SampleOutcome> out;
  if (timings) timings->assign(tasks.size(), {});
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (!producers[i].empty()) holders_[tasks[i].point.key] = producers[i];
    out.push_back(protocol::SampleOutcomeOf(results[i]));
    if (timings) (*timings)[i].wall_seconds = results[i].wall_seconds();
  }
  return out;
}

std::vector<sampling::GeometryChangeResult> RemoteExecutor::RunGeometryChangeTasks(
    const std::vector<sampling::GeometryChangeTask>& tasks, sampling::SampleEvaluator&,
    std::vector<sampling::TaskTiming>* timings) {
  std::vector<v1::TaskPayload> payloads;
  std::vector<std::vector<std::string>> preferred;
  for (const auto& t : tasks) {
    // The workers holding the samples' root solids, so that any worker
    // can ask them instead of evaluating again (tasks.proto "Geometry
    // blobs").
    v1::TaskPayload p = protocol::GeometryChangePayload(t);
    if (auto it = holders_.find(t.point_a.key); it != holders_.end()) p.set_solid_holder_a(it->second);
    if (auto it = holders_.find(t.point_b.key); it != holders_.end()) p.set_solid_holder_b(it->second);
    payloads.push_back(std::move(p));
    // Lease affinity: the workers holding the solids in memory.
    std::vector<std::string> holders;
    for (const auto* key : {&t.point_a.key, &t.point_b.key})
      if (auto it = holders_.find(*key);
          it != holders_.end() && std::find(holders.begin(), holders.end(), it->second) == holders.end())
        holders.push_back(it->second);
    preferred.push_back(std::move(holders));
  }
  BeginBatch(/*samples=*/false, tasks.size());
  auto results = Run(payloads, preferred);
  EndBatch(results);
  std::vector<sampling::GeometryChangeResult> out;
  if (timings) timings->assign(tasks.size(), {});
  for (std::size_t i = 0; i < results.size(); ++i) {
    out.push_back({results[i].geometry_change(), results[i].cpu_seconds()});
    if (timings) (*timings)[i].wall_seconds = results[i].wall_seconds();
  }
  return out;
}

void RemoteExecutor::SamplingFinished() {
  publish_started_ = std::chrono::steady_clock::now();
  {
    std::lock_guard lock(impl_.schedule_mu);
    if (auto it = impl_.schedules.find(job_id_); it != impl_.schedules.end())
      it->second.publish_started = publish_started_;
  }
  impl_.ForgetShares(bundle_digest_);
}

std::vector<design::SweptVolumeResult> RemoteExecutor::RunSweptVolumeTasks(
    const std::vector<pipeline::SweptVolumeTask>& tasks) {
  std::vector<v1::TaskPayload> payloads;
  for (const auto& t : tasks) {
    v1::TaskPayload p = protocol::SamplePayload({t.point});
    p.set_kind(v1::TASK_KIND_SWEPT_VOLUME);
    p.mutable_swept()->set_node_path(t.node_path);
    payloads.push_back(std::move(p));
  }
  std::vector<design::SweptVolumeResult> out;
  for (const v1::TaskResult& result : Run(payloads)) {
    const v1::SweptVolumeResult& r = result.swept_volume();
    design::SweptVolumeResult s;
    s.volume = r.volume();
    s.triangles = r.triangles();
    s.time_steps = r.time_steps();
    s.active_voxels = r.active_voxels();
    s.surface_sha256 = r.surface_sha256();
    if (!r.surface_blob().empty()) {
      impl_.store->AddJobBlob(job_id_, r.surface_blob());
      // The blob's digest is the surface's SHA-256 when it holds it.
      if (r.surface_blob() == r.surface_sha256()) s.surface_bytes = impl_.blobs->Read(r.surface_blob());
    }
    out.push_back(std::move(s));
  }
  return out;
}

pipeline::CacheAssembly RemoteExecutor::CacheSubtrees(const sampling::Form& form) {
  for (const auto& row : impl_.store->Subtrees(job_id_))
    if (!row.blob_digest.empty() && !impl_.blobs->Contains(row.blob_digest))
      impl_.Event(job_id_, "blob_missing",
                  "subtree " + row.key + " names blob " + row.blob_digest + ", which is not in the store");
  return CollectSubtreesFromStore(*impl_.store, *impl_.blobs, job_id_, job_.design, form);
}

v1::CachePlanReport RemoteExecutor::RunCachePlan(const v1::CachePlanInput& input) {
  return impl_.PlanCacheOnWorkers(job_id_, digest_, subdivisions_, input);
}

std::vector<v1::TaskResult> RemoteExecutor::Run(const std::vector<v1::TaskPayload>& payloads,
                                                const std::vector<std::vector<std::string>>& preferred,
                                                std::vector<std::string>* producers) {
  std::vector<std::string> bytes, keys;
  std::vector<int> kinds;
  for (const auto& p : payloads) {
    bytes.push_back(p.SerializeAsString());
    keys.push_back(protocol::TaskKey(p, digest_, subdivisions_));
    kinds.push_back(static_cast<int>(p.kind()));
  }
  auto results = impl_.RunTasks(job_id_, bytes, keys, kinds, preferred, producers);
  std::vector<v1::TaskResult> out(results.size());
  for (std::size_t i = 0; i < results.size(); ++i) out[i].ParseFromString(results[i]);
  return out;
}

void RemoteExecutor::BeginBatch(bool samples, std::size_t size) {
  batches_.push_back({samples, static_cast<double>(size), 0});
  Publish(/*batch_begins=*/true);
}

void RemoteExecutor::EndBatch(const std::vector<v1::TaskResult>& results) {
  if (results.empty()) return;
  for (const auto& r : results) batches_.back().cpu_seconds += r.cpu_seconds();
  Publish(/*batch_begins=*/false);
}

void RemoteExecutor::Publish(bool batch_begins) {
  std::lock_guard lock(impl_.schedule_mu);
  auto [it, created] = impl_.schedules.try_emplace(job_id_);
  auto& sch = it->second;
  if (created) sch.work_history.emplace_back(std::chrono::steady_clock::now(), EtaProgress{});
  if (batch_begins) sch.work_at_batch_start = sch.work;
  sch.input.batches = batches_;
  sch.input.max_depth = sampling_.max_depth;
  sch.input.max_samples = static_cast<double>(sampling_.max_samples);
  sch.input.dimensions = static_cast<int>(dims_);
}

}  // namespace fabatlas::coordinator
