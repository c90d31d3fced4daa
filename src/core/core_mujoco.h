// MuJoCo ownership and process-global hooks, wrapped in one place.
//
// MuJoCo's default error handler prints "Press Enter to exit", reads stdin and
// writes MUJOCO_LOG.TXT; its warning handler prints. InstallMujocoHandlers()
// replaces both once per process: warnings are collected (and counted by MuJoCo
// in mjData::warning), errors print one line and end the process with exit
// code 1 after running the registered cleanup (e.g. removing a staging folder).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

namespace vlab {

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

/// Replaces MuJoCo's error and warning handlers (idempotent).
void InstallMujocoHandlers();

/// Sets the action run before the process exits on a MuJoCo error (or clears it
/// with nullptr). Only one is kept.
void SetMujocoErrorCleanup(std::function<void()> cleanup);

/// Warning texts MuJoCo reported since the last call, oldest first.
std::vector<std::string> TakeMujocoWarningTexts();

/// Loads and compiles an MJCF file. Throws InputError "scene 'PATH': REASON"
/// when the file is missing or does not compile.
ModelPtr LoadModel(const std::string& path);

/// Loads an MJCF document held in memory (name is used in messages and for
/// resolving nothing else: the document must not include other files).
ModelPtr LoadModelFromString(const std::string& name, const std::string& xml);

/// Allocates mjData for a model; throws std::runtime_error on failure.
DataPtr MakeData(const mjModel* model);

/// Copies into `dst` (made for the same model) what drawing `src` reads, for a
/// renderer on another thread: the scalars and every array of mjData (positions,
/// frames, contacts, forces), the first ncon contacts, the first nefc entries of
/// the per-constraint vectors; not the constraint matrices (efc_J, efc_JT, efc_AR
/// and their sparsity, efc_KBIP) nor the stack. A scene drawn from `dst` is the
/// scene drawn from `src`, at a fraction of mj_copyData's cost: for a PA10 with
/// the default njmax the matrices and stack are 15 MB of a 16 MB copy.
/// `dst` is no state to step from.
void CopyDrawnState(const mjModel* m, const mjData* src, mjData* dst);

/// Short lowercase name of a MuJoCo warning index ("contactfull", "badqacc", ...).
const char* WarningName(int warning_index);
/// Index of a warning name, or -1.
int WarningIndex(const std::string& name);
/// True for warnings that mean the simulation diverged (bad qpos/qvel/qacc).
bool IsDivergenceWarning(int warning_index);

/// MuJoCo's version string, e.g. "2.2.2".
std::string MujocoVersion();

}  // namespace vlab
