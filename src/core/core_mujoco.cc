#include "core/core_mujoco.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>

#include <mujoco/mjxmacro.h>

#include "core/core_errors.h"
#include "core/core_input_file.h"

namespace vlab {

namespace {

std::mutex g_mutex;
std::vector<std::string> g_warnings;
std::function<void()> g_cleanup;

void OnMujocoError(const char* msg) {
  // MuJoCo errors are not recoverable (the engine's state is undefined after one)
  std::fprintf(stderr, "vlab: MuJoCo error: %s\n", msg);
  std::function<void()> cleanup;
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    cleanup = g_cleanup;
  }
  if (cleanup) cleanup();
  std::fflush(stderr);
  std::_Exit(1);
}

void OnMujocoWarning(const char* msg) {
  std::lock_guard<std::mutex> lock(g_mutex);
  if (g_warnings.size() < 1000) g_warnings.emplace_back(msg);
}

constexpr const char* kWarningNames[mjNWARNING] = {
    "inertia", "contactfull", "cnstrfull", "vgeomfull", "badqpos", "badqvel", "badqacc", "badctrl",
};

// MuJoCo's compiler messages span lines: make them one line
std::string OneLine(const char* text) {
  std::string out;
  for (const char* c = text; *c; ++c) {
    if (*c == '\n') {
      if (!out.empty() && out.back() != ' ') out += "; ";
    } else {
      out += *c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out;
}

// The file="..." of each <include> element of an MJCF text, comments left out.
std::vector<std::string> IncludedFiles(const std::string& text) {
  std::string xml;
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t comment = text.find("<!--", at);
    xml.append(text, at, comment == std::string::npos ? std::string::npos : comment - at);
    if (comment == std::string::npos) break;
    const std::size_t end = text.find("-->", comment + 4);
    at = end == std::string::npos ? text.size() : end + 3;
  }
  std::vector<std::string> files;
  for (std::size_t at = xml.find("<include"); at != std::string::npos; at = xml.find("<include", at + 1)) {
    const std::size_t end = xml.find('>', at);
    const std::size_t attribute = xml.find("file", at);
    if (end == std::string::npos || attribute == std::string::npos || attribute > end) continue;
    const std::size_t open = xml.find_first_of("\"'", attribute);
    if (open == std::string::npos || open > end) continue;
    const std::size_t close = xml.find(xml[open], open + 1);
    if (close == std::string::npos || close > end) continue;
    files.push_back(xml.substr(open + 1, close - open - 1));
  }
  return files;
}

// The scene and the files it includes, before MuJoCo opens them: regular files
// (a FIFO would block MuJoCo, a device fill memory), UTF-8, at most
// kMaxSceneBytes. MuJoCo resolves an include relative to the top scene's folder.
void CheckSceneFiles(const std::string& path, const std::string& what, const std::filesystem::path& top_dir,
                     int depth) {
  const std::string xml = ReadInputFile(path, what, kMaxSceneBytes);
  if (depth >= 8) return;  // MuJoCo itself refuses what nests deeper than it allows
  for (const std::string& file : IncludedFiles(xml)) {
    const std::filesystem::path included =
        std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : top_dir / file;
    CheckSceneFiles(included.string(), what + ": include '" + file + "'", top_dir, depth + 1);
  }
}

}  // namespace

void InstallMujocoHandlers() {
  mju_user_error = OnMujocoError;
  mju_user_warning = OnMujocoWarning;
}

void SetMujocoErrorCleanup(std::function<void()> cleanup) {
  std::lock_guard<std::mutex> lock(g_mutex);
  g_cleanup = std::move(cleanup);
}

std::vector<std::string> TakeMujocoWarningTexts() {
  std::lock_guard<std::mutex> lock(g_mutex);
  std::vector<std::string> out;
  out.swap(g_warnings);
  return out;
}

ModelPtr LoadModel(const std::string& path) {
  InstallMujocoHandlers();
  CheckSceneFiles(path, "scene '" + path + "'", std::filesystem::path(path).parent_path(), 0);
  char error[1024] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  if (!m) throw InputError("scene '" + path + "': " + (error[0] ? OneLine(error) : "failed to compile"));
  return ModelPtr(m);
}

ModelPtr LoadModelFromString(const std::string& name, const std::string& xml) {
  InstallMujocoHandlers();
  // mjVFS is large: keep it on the heap
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(xml.size())) != 0) {
    throw InputError("scene '" + name + "': cannot create in-memory file");
  }
  const int index = mj_findFileVFS(vfs.get(), name.c_str());
  std::memcpy(vfs->filedata[index], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(name.c_str(), vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (!m) throw InputError("scene '" + name + "': " + (error[0] ? OneLine(error) : "failed to compile"));
  return ModelPtr(m);
}

DataPtr MakeData(const mjModel* model) {
  mjData* d = mj_makeData(model);
  if (!d) throw std::runtime_error("mj_makeData failed");
  return DataPtr(d);
}

const char* WarningName(int i) { return (i >= 0 && i < mjNWARNING) ? kWarningNames[i] : "unknown"; }

int WarningIndex(const std::string& name) {
  for (int i = 0; i < mjNWARNING; ++i) {
    if (name == kWarningNames[i]) return i;
  }
  return -1;
}

bool IsDivergenceWarning(int i) { return i == mjWARN_BADQPOS || i == mjWARN_BADQVEL || i == mjWARN_BADQACC; }

void CopyDrawnState(const mjModel* m, const mjData* src, mjData* dst) {
  // the scalars (not the sizes and the stack's top: those are dst's own)
  dst->maxuse_stack = src->maxuse_stack;
  dst->maxuse_con = src->maxuse_con;
  dst->maxuse_efc = src->maxuse_efc;
  std::memcpy(dst->warning, src->warning, sizeof(src->warning));
  std::memcpy(dst->timer, src->timer, sizeof(src->timer));
  std::memcpy(dst->solver, src->solver, sizeof(src->solver));
  dst->solver_iter = src->solver_iter;
  dst->solver_nnz = src->solver_nnz;
  std::memcpy(dst->solver_fwdinv, src->solver_fwdinv, sizeof(src->solver_fwdinv));
  dst->ne = src->ne;
  dst->nf = src->nf;
  dst->nefc = src->nefc;
  dst->ncon = src->ncon;
  dst->time = src->time;
  std::memcpy(dst->energy, src->energy, sizeof(src->energy));
  // the arrays, by MuJoCo's own list of them (mjxmacro.h): a field added to mjData is copied
  MJDATA_POINTERS_PREAMBLE(m)
  (void)nv;
  (void)njmax;
#define X(type, name, nr, nc)                                                                      \
  {                                                                                                \
    std::size_t rows = static_cast<std::size_t>(m->nr);                                            \
    const std::size_t cols = static_cast<std::size_t>(nc);                                         \
    const bool constraint = std::strncmp(#name, "efc_", 4) == 0;                                   \
    if (&m->nr == &m->nconmax) rows = static_cast<std::size_t>(src->ncon);                         \
    if (constraint && &m->nr == &m->njmax) rows = static_cast<std::size_t>(src->nefc);             \
    if (!(constraint && cols != 1)) std::memcpy(dst->name, src->name, sizeof(type) * rows * cols); \
  }
  MJDATA_POINTERS
#undef X
}

std::string MujocoVersion() { return mj_versionString(); }

}  // namespace vlab
