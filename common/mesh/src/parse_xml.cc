// The XML readers' shared parts (mesh_formats.h): expat over a whole document.
#include "fabatlas/error.h"
#include "mesh_formats.h"

namespace fabatlas::mesh::internal {

std::string_view LocalName(const char* name) {
  std::string_view n(name);
  const auto colon = n.rfind(':');
  return colon == std::string_view::npos ? n : n.substr(colon + 1);
}

void ParseXml(const std::filesystem::path& path, const std::string& format, const std::string& xml, void* data,
              XML_StartElementHandler start, XML_EndElementHandler end, XML_CharacterDataHandler characters) {
  XML_Parser parser = XML_ParserCreate(nullptr);
  XML_SetUserData(parser, data);
  XML_SetElementHandler(parser, start, end);
  if (characters) XML_SetCharacterDataHandler(parser, characters);
  const bool ok = XML_Parse(parser, xml.data(), static_cast<int>(xml.size()), 1) == XML_STATUS_OK;
  const std::string error = ok ? "" : XML_ErrorString(XML_GetErrorCode(parser));
  const auto line = XML_GetCurrentLineNumber(parser);
  XML_ParserFree(parser);
  if (!ok) throw InputError(path.string() + ": " + format + " line " + std::to_string(line) + ": " + error);
}

}  // namespace fabatlas::mesh::internal
