#include "core/core_mujoco.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>

#include <mujoco/mjxmacro.h>

#include "core/core_errors.h"

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
  std::ifstream probe(path);
  if (!probe) throw InputError("scene '" + path + "': cannot open file");
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
#define X(type, name, nr, nc)                                                                  \
  {                                                                                             \
    std::size_t rows = static_cast<std::size_t>(m->nr);                                         \
    const std::size_t cols = static_cast<std::size_t>(nc);                                      \
    const bool constraint = std::strncmp(#name, "efc_", 4) == 0;                                \
    if (&m->nr == &m->nconmax) rows = static_cast<std::size_t>(src->ncon);                      \
    if (constraint && &m->nr == &m->njmax) rows = static_cast<std::size_t>(src->nefc);           \
    if (!(constraint && cols != 1)) std::memcpy(dst->name, src->name, sizeof(type) * rows * cols); \
  }
  MJDATA_POINTERS
#undef X
}

std::string MujocoVersion() { return mj_versionString(); }

}  // namespace vlab
