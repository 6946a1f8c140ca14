// 3MF packages: the model XML of the 3MF core specification in a ZIP
// container (PKWARE APPNOTE 6.3: local headers, central directory, end
// record; entries deflated with zlib's raw deflate).
#include "fabatlas/mesh/encode_3mf.h"

#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::mesh {
namespace {

void Put16(std::string* out, std::uint16_t v) {
  out->push_back(static_cast<char>(v & 0xff));
  out->push_back(static_cast<char>(v >> 8));
}
void Put32(std::string* out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out->push_back(static_cast<char>((v >> (8 * k)) & 0xff));
}

std::string RawDeflate(const std::string& data) {
  z_stream z{};
  if (deflateInit2(&z, Z_DEFAULT_COMPRESSION, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw ResourceError("3mf: zlib deflateInit2 failed");
  std::string out(deflateBound(&z, data.size()), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw ResourceError("3mf: zlib deflate failed");
  return out;
}

struct Entry {
  std::string name, data;
};

// A ZIP archive of deflated entries, every date 1980-01-01 00:00.
std::string Zip(const std::vector<Entry>& entries) {
  if (entries.size() > 0xffff) throw InputError("3mf: too many entries");
  std::string out, central;
  for (const Entry& e : entries) {
    const std::string packed = RawDeflate(e.data);
    if (e.data.size() > 0xffffffffu || packed.size() > 0xffffffffu || out.size() > 0xffffffffu)
      throw InputError("3mf: mesh too large for a ZIP without ZIP64 (4 GiB)");
    const auto crc = static_cast<std::uint32_t>(
        crc32(0L, reinterpret_cast<const Bytef*>(e.data.data()), static_cast<uInt>(e.data.size())));
    const auto offset = static_cast<std::uint32_t>(out.size());
    // Local file header.
    Put32(&out, 0x04034b50);
    Put16(&out, 20);    // version needed: 2.0 (deflate)
    Put16(&out, 0);     // flags
    Put16(&out, 8);     // method: deflate
    Put16(&out, 0);     // time
    Put16(&out, 0x21);  // date: 1980-01-01
    Put32(&out, crc);
    Put32(&out, static_cast<std::uint32_t>(packed.size()));
    Put32(&out, static_cast<std::uint32_t>(e.data.size()));
    Put16(&out, static_cast<std::uint16_t>(e.name.size()));
    Put16(&out, 0);  // extra length
    out += e.name;
    out += packed;
    // Central directory record.
    Put32(&central, 0x02014b50);
    Put16(&central, 20);  // made by
    Put16(&central, 20);  // needed
    Put16(&central, 0);
    Put16(&central, 8);
    Put16(&central, 0);
    Put16(&central, 0x21);
    Put32(&central, crc);
    Put32(&central, static_cast<std::uint32_t>(packed.size()));
    Put32(&central, static_cast<std::uint32_t>(e.data.size()));
    Put16(&central, static_cast<std::uint16_t>(e.name.size()));
    Put16(&central, 0);  // extra
    Put16(&central, 0);  // comment
    Put16(&central, 0);  // disk
    Put16(&central, 0);  // internal attributes
    Put32(&central, 0);  // external attributes
    Put32(&central, offset);
    central += e.name;
  }
  const auto central_offset = static_cast<std::uint32_t>(out.size());
  out += central;
  Put32(&out, 0x06054b50);
  Put16(&out, 0);
  Put16(&out, 0);
  Put16(&out, static_cast<std::uint16_t>(entries.size()));
  Put16(&out, static_cast<std::uint16_t>(entries.size()));
  Put32(&out, static_cast<std::uint32_t>(central.size()));
  Put32(&out, central_offset);
  Put16(&out, 0);
  return out;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

}  // namespace

std::string Encode3mf(const TriangleMesh& mesh) { return Encode3mfObjects({{"", &mesh, false, {}}}); }

std::string Encode3mfObjects(const std::vector<Object3mf>& objects) {
  const std::string content_types =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">"
      "<Default Extension=\"rels\" ContentType=\"application/vnd.openxmlformats-package.relationships+xml\"/>"
      "<Default Extension=\"model\" ContentType=\"application/vnd.ms-package.3dmanufacturing-3dmodel+xml\"/>"
      "</Types>\n";
  const std::string rels =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
      "<Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
      "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/>"
      "</Relationships>\n";
  std::string model =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<model unit=\"millimeter\" xml:lang=\"en-US\" "
      "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n"
      "<metadata name=\"Application\">fabatlas</metadata>\n"
      "<resources>\n";
  // The distinct colours, in order of first use (sRGB, as displaycolor is).
  std::vector<std::string> colours;
  std::vector<int> pindex;
  for (const Object3mf& o : objects) {
    if (!o.mesh) throw InputError("3mf: an object without a mesh");
    if (!o.coloured) {
      pindex.push_back(-1);
      continue;
    }
    char hex[16];
    auto byte = [](double v) { return static_cast<unsigned>(v <= 0 ? 0 : v >= 1 ? 255 : v * 255 + 0.5); };
    std::snprintf(hex, sizeof hex, "#%02X%02X%02X%02X", byte(o.rgba[0]), byte(o.rgba[1]), byte(o.rgba[2]),
                  byte(o.rgba[3]));
    std::size_t k = 0;
    while (k < colours.size() && colours[k] != hex) ++k;
    if (k == colours.size()) colours.push_back(hex);
    pindex.push_back(static_cast<int>(k));
  }
  const int first_id = colours.empty() ? 1 : 2;
  if (!colours.empty()) {
    model += "<basematerials id=\"1\">\n";
    for (const std::string& c : colours) {
      const std::string name = c.substr(6) == "FF" ? c.substr(0, 7) : c;
      model += "<base name=\"" + name + "\" displaycolor=\"" + c + "\"/>\n";
    }
    model += "</basematerials>\n";
  }
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const TriangleMesh& mesh = *objects[i].mesh;
    std::string name;  // XML-escaped
    for (char ch : objects[i].name)
      name += ch == '&' ? "&amp;" : ch == '<' ? "&lt;" : ch == '>' ? "&gt;" : ch == '"' ? "&quot;" : std::string(1, ch);
    model += "<object id=\"" + std::to_string(first_id + i) + "\" type=\"model\"" +
             (name.empty() ? "" : " name=\"" + name + "\"") +
             (pindex[i] < 0 ? "" : " pid=\"1\" pindex=\"" + std::to_string(pindex[i]) + "\"") +
             ">\n<mesh>\n<vertices>\n";
    model.reserve(model.size() + mesh.vertices.size() * 48 + mesh.triangles.size() * 40);
    for (const auto& v : mesh.vertices)
      model += "<vertex x=\"" + Number(v[0]) + "\" y=\"" + Number(v[1]) + "\" z=\"" + Number(v[2]) + "\"/>\n";
    model += "</vertices>\n<triangles>\n";
    for (const auto& t : mesh.triangles)
      model += "<triangle v1=\"" + std::to_string(t[0]) + "\" v2=\"" + std::to_string(t[1]) + "\" v3=\"" +
               std::to_string(t[2]) + "\"/>\n";
    model += "</triangles>\n</mesh>\n</object>\n";
  }
  model += "</resources>\n<build>\n";
  for (std::size_t i = 0; i < objects.size(); ++i)
    model += "<item objectid=\"" + std::to_string(first_id + i) + "\"/>\n";
  model += "</build>\n</model>\n";
  return Zip({{"[Content_Types].xml", content_types}, {"_rels/.rels", rels}, {"3D/3dmodel.model", model}});
}

}  // namespace fabatlas::mesh
