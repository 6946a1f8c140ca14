// A place in a user's file and the input error naming it (fabatlas/source_place.h).
#include "fabatlas/source_place.h"

#include "fabatlas/error.h"

namespace fabatlas {

std::string SourcePlace::str() const {
  if (line <= 0) return file;
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

void FailAt(const SourcePlace& place, const std::string& what) { throw InputError(place.str() + ": " + what); }

}  // namespace fabatlas
