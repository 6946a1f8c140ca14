// Internal to fabatlas_mesh: the readers of the archive and XML formats
// ReadMesh dispatches to (read_mesh.h documents what each accepts).
#pragma once

#include <expat.h>

#include <filesystem>
#include <string>
#include <string_view>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh::internal {

// True when `data` starts with a ZIP local file header ("PK\3\4").
bool IsZip(std::string_view data);

// The uncompressed bytes of the entry `name` of the ZIP archive `data`
// (stored or deflated; no ZIP64, no encryption), or of its first entry when
// `name` is empty. Entries larger than 1 GiB uncompressed are refused.
// Throws InputError "PATH: ..." for a damaged archive or a missing entry.
std::string ZipEntry(const std::filesystem::path& path, std::string_view data, const std::string& name);

// An XML element's or attribute's name without its namespace prefix
// ("m:color" -> "color").
std::string_view LocalName(const char* name);

// Runs expat over `xml`, calling the handlers (`characters` may be null)
// with `data`. Throws InputError "PATH: FORMAT line N: <expat's message>"
// for text that is not well-formed XML.
void ParseXml(const std::filesystem::path& path, const std::string& format, const std::string& xml, void* data,
              XML_StartElementHandler start, XML_EndElementHandler end, XML_CharacterDataHandler characters);

// 3MF core: every build item's object (its mesh, or its components',
// recursively) under the item's and components' transforms; coordinates as
// stored (the unit attribute is ignored, as OpenSCAD 2021.01 ignores it). `data` is the whole .3mf archive.
TriangleMesh Read3mf(const std::filesystem::path& path, std::string_view data);

// AMF: every object's vertices and every volume's triangles; coordinates
// as stored (the unit attribute is ignored, as OpenSCAD 2021.01 ignores it). `data` is the XML text or a ZIP holding
// it.
TriangleMesh ReadAmf(const std::filesystem::path& path, std::string_view data);

// read_ply.cc: a PLY file's bytes as a mesh. Throws InputError "PATH: ..."
// for anything malformed.
TriangleMesh ReadPly(const std::filesystem::path& path, std::string_view data);

}  // namespace fabatlas::mesh::internal
