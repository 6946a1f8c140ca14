// RemovePart: a discrete edit of a works-like prototype (Koo et al. Sec. 6:
// "discrete edits such as adding/removing parts"; the jewellery box of
// Sec. 8). The caller solves the result again.
#include <algorithm>
#include <cctype>
#include <set>

#include "fabatlas/error.h"
#include "fabatlas/prototype/prototype.h"

namespace fabatlas::prototype {
namespace {

// The part named by a reference "part", "part.x0" or "part.piece.y1".
std::string Owner(const std::string& ref) { return ref.substr(0, ref.find('.')); }

// Whether an expression names one of `parts` ("part." preceded by no name character).
bool Names(const std::string& expression, const std::set<std::string>& parts) {
  for (const std::string& p : parts)
    for (auto at = expression.find(p + "."); at != std::string::npos; at = expression.find(p + ".", at + 1)) {
      char before = at ? expression[at - 1] : ' ';
      if (!(std::isalnum(static_cast<unsigned char>(before)) || before == '_' || before == '.')) return true;
    }
  return false;
}

}  // namespace

Prototype RemovePart(const Prototype& p, const std::string& part) {
  if (p.PartIndex(part) < 0) throw InputError(p.file + ": cannot remove unknown part '" + part + "'");
  // The part and everything hanging from it by joints.
  std::set<std::string> gone{part};
  for (bool grew = true; grew;) {
    grew = false;
    for (const Joint& j : p.joints)
      if (gone.count(j.parent) && gone.insert(j.child).second) grew = true;
  }
  Prototype out = p;
  out.parts.clear();
  for (const Part& q : p.parts)
    if (!gone.count(q.name)) out.parts.push_back(q);
  std::set<std::string> gone_joints;
  out.joints.clear();
  for (const Joint& j : p.joints) {
    if (gone.count(j.child))
      gone_joints.insert(j.name);
    else
      out.joints.push_back(j);
  }
  for (Configuration& c : out.configurations)
    for (const std::string& j : gone_joints) c.values.erase(j);

  auto keep = [&](std::vector<std::string>& refs) {
    refs.erase(std::remove_if(refs.begin(), refs.end(), [&](const std::string& r) { return gone.count(Owner(r)) > 0; }),
               refs.end());
    return !refs.empty();
  };
  out.relationships.clear();
  for (Relationship r : p.relationships) {
    bool kept = true;
    switch (r.type) {
      case RelationType::kCover:
        kept = keep(r.a) && keep(r.b);
        break;
      case RelationType::kFit:
        kept = !gone.count(Owner(r.b[0])) && keep(r.a);
        break;
      case RelationType::kSupport:
        r.pairs.erase(
            std::remove_if(r.pairs.begin(), r.pairs.end(),
                           [&](const auto& pr) { return gone.count(Owner(pr.first)) || gone.count(Owner(pr.second)); }),
            r.pairs.end());
        kept = !r.pairs.empty();
        break;
      case RelationType::kFlush:
        kept = !gone.count(Owner(r.a[0])) && !gone.count(Owner(r.a[1]));
        break;
      case RelationType::kGeometric:
        kept = !Names(r.expression, gone);
        break;
    }
    if (kept) out.relationships.push_back(r);
  }
  return out;
}

}  // namespace fabatlas::prototype
