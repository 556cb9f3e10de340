// The files an MJCF model is made of, found by reading its XML: the model itself, every
// <include file=...> (recursively) and every other file an element names (meshes, textures,
// height fields). Used to name the right file in error messages and to refuse an output that
// would overwrite an input.
#ifndef MJTETHER_PLUGIN_MODEL_FILES_H_
#define MJTETHER_PLUGIN_MODEL_FILES_H_

#include <string>
#include <vector>

namespace mjtether {

// The model file first, then every file it names that exists (relative names are tried
// against the including file's directory, the model's directory and its compiler meshdir /
// texturedir). Files that cannot be read are left out.
std::vector<std::string> ModelFiles(const std::string& path);

// An Attach error "PATH: <text name="X">: ..." whose element X is declared in an included
// file rather than in PATH itself, rewritten as "FILE (included from PATH): <text ...": ...".
// Any other message is returned unchanged.
std::string NameIncludedFile(const std::string& path, const std::string& error);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_MODEL_FILES_H_
