#include "model_files.h"

#include <fstream>
#include <regex>
#include <sstream>

namespace mjtether {
namespace {

std::string Directory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

bool ReadFile(const std::string& path, std::string* text) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::ostringstream s;
  s << f.rdbuf();
  *text = s.str();
  return true;
}

bool Exists(const std::string& path) { return std::ifstream(path).good(); }

bool EndsWithXml(const std::string& s) {
  return s.size() >= 4 &&
         (s.compare(s.size() - 4, 4, ".xml") == 0 || s.compare(s.size() - 4, 4, ".XML") == 0);
}

// Every value of an attribute `name` in the text.
std::vector<std::string> Attributes(const std::string& text, const std::string& name) {
  std::vector<std::string> values;
  const std::regex re("\\b" + name + "\\s*=\\s*(\"([^\"]*)\"|'([^']*)')");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it) {
    values.push_back((*it)[2].matched ? (*it)[2].str() : (*it)[3].str());
  }
  return values;
}

void Collect(const std::string& file, const std::string& top_dir, std::vector<std::string>* dirs,
             std::vector<std::string>* files, int depth) {
  std::string text;
  if (depth > 32 || !ReadFile(file, &text)) return;
  for (const char* key : {"meshdir", "texturedir"}) {
    for (const std::string& d : Attributes(text, key)) {
      dirs->push_back(!d.empty() && d[0] == '/' ? d : top_dir + d + (d.empty() ? "" : "/"));
    }
  }
  for (const std::string& name : Attributes(text, "file")) {
    if (name.empty()) continue;
    std::vector<std::string> candidates;
    if (name[0] == '/') {
      candidates.push_back(name);
    } else {
      candidates.push_back(Directory(file) + name);
      candidates.push_back(top_dir + name);
      for (const std::string& d : *dirs) candidates.push_back(d + name);
    }
    for (const std::string& c : candidates) {
      bool known = false;
      for (const std::string& f : *files) known |= f == c;
      if (known || !Exists(c)) continue;
      files->push_back(c);
      if (EndsWithXml(c)) Collect(c, top_dir, dirs, files, depth + 1);
    }
  }
}

bool Declares(const std::string& file, const std::string& element) {
  std::string text;
  if (!ReadFile(file, &text)) return false;
  return text.find("name=\"" + element + "\"") != std::string::npos ||
         text.find("name='" + element + "'") != std::string::npos;
}

}  // namespace

std::vector<std::string> ModelFiles(const std::string& path) {
  std::vector<std::string> files = {path}, dirs;
  Collect(path, Directory(path), &dirs, &files, 0);
  return files;
}

std::string NameIncludedFile(const std::string& path, const std::string& error) {
  const std::string prefix = path + ": <text name=\"";
  if (error.rfind(prefix, 0) != 0) return error;
  const size_t end = error.find("\">", prefix.size());
  if (end == std::string::npos) return error;
  const std::string element = error.substr(prefix.size(), end - prefix.size());
  if (Declares(path, element)) return error;
  const std::vector<std::string> files = ModelFiles(path);
  for (size_t i = 1; i < files.size(); ++i) {
    if (EndsWithXml(files[i]) && Declares(files[i], element)) {
      return files[i] + " (included from " + path + ")" + error.substr(path.size());
    }
  }
  return error;
}

}  // namespace mjtether
