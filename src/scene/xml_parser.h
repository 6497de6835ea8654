// Mitsuba 3 XML scene files -> a tree of object declarations (no plugin is instantiated here).
//
// Handles <scene version>, <default>, $name substitution in every attribute, -D overrides, <include>, <path>,
// id / <ref> / <alias>, <transform> with translate/rotate/scale/matrix/lookat, and the value tags float,
// integer, boolean, string, rgb, spectrum, point and vector. Every error is a LoadError "file:line: message".
#pragma once
#include "scene/properties.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace penumbra {

struct XmlNode;

// A nested object of a parent (or of the scene): declared inline, or a <ref> to an object declared elsewhere.
struct XmlChild {
    std::string name;              // the `name` attribute (empty when absent)
    std::string ref_id;            // the id of a <ref>; empty for inline declarations
    std::shared_ptr<XmlNode> node; // the declared object, or the referenced one (not owned: XmlScene::ids owns it)
    SourceLocation location;       // where the declaration or <ref> appears
};

// One object declaration, e.g. <bsdf type="diffuse" id="white">.
struct XmlNode {
    ObjectKind kind = ObjectKind::Shape; // from the tag name
    std::string type;                    // plugin name
    std::string id;                      // empty when absent
    SourceLocation location;
    Properties props;               // the plain values; nested objects are in `children`
    std::vector<XmlChild> children; // nested objects in declaration order
};

struct XmlScene {
    SourceLocation location;                             // the <scene> element
    std::vector<XmlChild> objects;                       // top-level objects in document order
    std::map<std::string, std::shared_ptr<XmlNode>> ids; // every id and alias
    std::vector<std::string> search_paths;               // scene file's directory first, then <path> entries
    Properties props;                                    // values directly in <scene> (Mitsuba's scene parameters)
};

// Parses a scene file. `defines` override <default> values (mitsuba's -D name=value).
XmlScene parse_xml_file(const std::string& path, const std::map<std::string, std::string>& defines = {});
// Parses a scene from a string; relative file names resolve against `base_dir`. Locations read
// "<string>:line".
XmlScene parse_xml_string(const std::string& xml, const std::string& base_dir = ".",
                          const std::map<std::string, std::string>& defines = {});

} // namespace penumbra
