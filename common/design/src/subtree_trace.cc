// What a subtree computed with a subtree cache keeps beside its geometry
// (openscad_node.h, SubtreeTrace): its cache entry with the trace's memory
// counted, and the records a cache hit brings back.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "openscad_node.h"

namespace fabatlas::design {

namespace {

// Memory `t` holds: its own strings and meshes and its children's traces.
std::size_t TraceBytes(const SubtreeTrace& t) {
  std::size_t bytes = sizeof(SubtreeTrace) + t.topology.capacity() + t.op.capacity();
  for (const auto& c : t.children) bytes += sizeof(std::string) + c.capacity();
  for (const auto& c : t.child_paths) bytes += sizeof(std::string) + c.capacity();
  for (const auto& c : t.child_traces) bytes += sizeof(c) + (c ? TraceBytes(*c) : 0);
  for (const OutsideMesh& m : t.outside) {
    bytes += sizeof(OutsideMesh) + m.what.capacity() + m.key.capacity();
    if (m.mesh)
      bytes += sizeof(mesh::TriangleMesh) + m.mesh->vertices.capacity() * sizeof(m.mesh->vertices[0]) +
               m.mesh->triangles.capacity() * sizeof(m.mesh->triangles[0]);
  }
  return bytes;
}

}  // namespace

CachedSubtree EntryOf(geometry::Solid solid, std::shared_ptr<const SubtreeTrace> trace) {
  CachedSubtree entry;
  entry.solid = std::move(solid);
  if (trace && (!trace->op.empty() || !trace->outside.empty())) {
    entry.trace_bytes = TraceBytes(*trace);
    entry.trace = std::move(trace);
  }
  return entry;
}

void AppendDescendantRecords(const SubtreeTrace& trace, const std::string& path, std::vector<SubtreeRecord>* records) {
  for (std::size_t i = 0; i < trace.children.size() && i < trace.child_traces.size(); ++i) {
    const SubtreeTrace* child = trace.child_traces[i].get();
    if (!child || child->op.empty()) continue;  // found in a cache filled elsewhere: no record kept
    const std::string child_path = path + trace.child_paths[i];
    AppendDescendantRecords(*child, child_path, records);
    SubtreeRecord r;
    r.key = trace.children[i];
    r.topology = child->topology;
    r.path = child_path;
    r.op = child->op;
    r.from_cache = true;
    r.bytes = child->bytes;
    r.children = child->children;
    records->push_back(std::move(r));
  }
}

}  // namespace fabatlas::design
