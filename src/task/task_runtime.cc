#include "task/task_runtime.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <lua.hpp>

#include "core/core_errors.h"
#include "task/task_lua.h"
#include "task/task_program.h"

namespace vlab::task {

int IndexOf(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

namespace {

// 64-bit mix of the seed and a program index (splitmix64 finaliser)
std::uint64_t ProgramSeed(std::uint64_t seed, int index) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * static_cast<std::uint64_t>(index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

[[noreturn]] void Fail(const ProgramConfig& c, const std::string& what) {
  throw InputError((c.where.empty() ? c.script : c.where) + ": program: " + what);
}

std::unique_ptr<Robot> BindRobot(const ProgramConfig& c, const mjModel* m, Devices* devices, double period_s) {
  auto r = std::make_unique<Robot>();
  r->arm = devices->Find(c.robot);
  if (!r->arm || r->arm->kind() != bridge::DeviceKind::kArm) Fail(c, "robot: no arm device named '" + c.robot + "'");
  if (c.tip_site.empty()) Fail(c, "tip_site: required with a robot (the site at the tool flange)");
  try {
    r->model = control::RobotModel::Create(m, {c.base_body, c.tip_site});
  } catch (const std::invalid_argument& e) {
    Fail(c, e.what());
  }
  // the arm's joints from its state layout: "q[0]".. are in device order; names
  // come from the chain, matched by position in the arm's joint list
  const std::vector<std::string>& names = r->arm->state_names();
  int n = 0;
  while (IndexOf(names, "q[" + std::to_string(n) + "]") >= 0) ++n;
  r->arm_dof = n;
  const std::vector<std::string> arm_joints = r->arm->joint_names();
  for (const std::string& joint : r->model->joint_names()) {
    const int k = IndexOf(arm_joints, joint);
    if (k < 0 || k >= n) Fail(c, "chain joint '" + joint + "' is not a joint of arm '" + c.robot + "'");
    r->arm_index.push_back(k);
  }
  r->q_meas.setZero(r->model->dof());
  r->q_ref.setZero(r->model->dof());
  r->command.assign(1 + n, 0.0);
  r->planner = std::make_unique<MotionPlanner>(r->model.get(), period_s);
  // the arm's own joint speed limits where it gives them; else the defaults
  const std::vector<double> vmax = r->arm->velocity_limits();
  if (!vmax.empty()) {
    JointRateLimits rates = r->planner->rate_limits();
    for (std::size_t i = 0; i < r->arm_index.size(); ++i) {
      const int k = r->arm_index[i];
      if (k >= static_cast<int>(vmax.size()) || !(vmax[k] > 0) || !std::isfinite(vmax[k])) {
        Fail(c, "arm '" + c.robot + "': no valid speed limit for joint '" + r->model->joint_names()[i] + "'");
      }
      rates.v_rps[static_cast<long>(i)] = vmax[k];
    }
    r->planner->set_rate_limits(rates);
  }
  if (!c.wrench.empty()) {
    r->default_wrench = devices->Find(c.wrench);
    if (!r->default_wrench || r->default_wrench->kind() != bridge::DeviceKind::kWrench) {
      Fail(c, "wrench: no wrench device named '" + c.wrench + "'");
    }
  } else {
    for (const std::string& name : devices->Names()) {
      Channel* ch = devices->Find(name);
      if (ch->kind() == bridge::DeviceKind::kWrench) {
        r->default_wrench = r->default_wrench ? nullptr : ch;  // only when there is exactly one
        if (!r->default_wrench) break;
      }
    }
  }
  return r;
}

// the script line a program's coroutine waits at (0: none)
int WaitingLine(lua_State* co) {
  char where[256];
  ScriptWhere(co, where, sizeof where);
  const char* colon = std::strrchr(where, ':');
  return colon ? std::atoi(colon + 1) : 0;
}

}  // namespace

void CheckParamName(const std::string& name, const std::string& where) {
  const auto ident = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0])) ||
      !std::all_of(name.begin(), name.end(), ident)) {
    throw InputError(where + ": parameter '" + name + "': a name is letters, digits and '_', not first a digit");
  }
}

std::pair<std::string, std::string> ParseParam(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) throw InputError("--param '" + text + "': expected NAME=VALUE");
  CheckParamName(text.substr(0, eq), "--param '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

void CheckSyntax(const std::string& script) {
  if (!std::filesystem::is_regular_file(script)) throw InputError("script: no file '" + script + "'");
  lua_State* L = luaL_newstate();
  if (!L) throw std::runtime_error("task: cannot create a Lua state");
  std::string error;
  if (luaL_loadfilex(L, script.c_str(), "t") != LUA_OK) error = lua_tostring(L, -1);
  lua_close(L);
  if (!error.empty()) throw InputError(error + " (syntax error: nothing has run)");
}

struct Runtime::Impl {
  RuntimeConfig config;
  Devices* devices = nullptr;
  Blackboard board;
  std::vector<std::unique_ptr<Program>> programs;
  std::string error;
  std::vector<double> scratch;

  ~Impl() {
    for (auto& p : programs) {
      if (p->L) lua_close(p->L);
    }
  }

  bool Resume(Program& p);
  // one period of every program, in order; false at the first failure (error)
  bool ResumeAll(double t_s);
  // the log columns of the period (columns may be null)
  void WriteColumns(double* columns);
  bool SendCommands(Program& p);
};

Runtime::Runtime(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Runtime::~Runtime() = default;

std::unique_ptr<Runtime> Runtime::Create(const RuntimeConfig& config, const mjModel* model, Devices* devices) {
  auto impl = std::make_unique<Impl>();
  impl->config = config;
  impl->devices = devices;
  if (!(config.instruction_budget > 0)) throw InputError("task: instruction_budget must be > 0");
  for (std::size_t i = 0; i < config.programs.size(); ++i) {
    const ProgramConfig& c = config.programs[i];
    auto p = std::make_unique<Program>();
    p->config = c;
    p->index = static_cast<int>(i);
    p->label = c.robot.empty() ? std::filesystem::path(c.script).filename().string() : c.robot;
    p->period_s = config.period_s;
    p->markers_hold = config.markers_hold;
    p->markers_wait_s = config.markers_wait_s;
    p->devices = devices;
    p->board = &impl->board;
    p->sandbox.script_dir = std::filesystem::path(c.script).parent_path().string();
    if (p->sandbox.script_dir.empty()) p->sandbox.script_dir = ".";
    p->sandbox.seed = ProgramSeed(config.seed, p->index);
    p->sandbox.instruction_budget = config.instruction_budget;
    Program* raw = p.get();
    const auto print = config.print;
    p->sandbox.print = [raw, print](const std::string& text) {
      if (print) print(raw->label, raw->t_s, text);
    };
    for (const auto& other : impl->programs) {
      if (!c.robot.empty() && other->config.robot == c.robot)
        Fail(c, "robot: '" + c.robot + "' has two programs: one owner at a time");
    }
    if (!c.robot.empty()) {
      p->robot = BindRobot(c, model, devices, config.period_s);
      impl->board.robots.insert(c.robot);
    }
    p->L = luaL_newstate();
    if (!p->L) throw std::runtime_error("task: cannot create a Lua state");
    impl->programs.push_back(std::move(p));
    Program& prog = *impl->programs.back();
    OpenSandbox(prog.L, &prog.sandbox);
    OpenValues(prog.L);
    OpenApi(&prog);
    // the script: a syntax error is an input error before anything runs
    if (!std::filesystem::is_regular_file(c.script)) Fail(c, "script: no file '" + c.script + "'");
    if (luaL_loadfilex(prog.L, c.script.c_str(), "t") != LUA_OK) {
      throw InputError(std::string(lua_tostring(prog.L, -1)) + " (syntax error: nothing has run)");
    }
    prog.co = lua_newthread(prog.L);
    lua_pushvalue(prog.L, -2);
    lua_xmove(prog.L, prog.co, 1);                              // the chunk, as the coroutine's body
    lua_setfield(prog.L, LUA_REGISTRYINDEX, "vlab.coroutine");  // keeps the thread alive
    lua_pop(prog.L, 1);
  }
  return std::unique_ptr<Runtime>(new Runtime(std::move(impl)));
}

std::vector<std::string> Runtime::Columns() const {
  std::vector<std::string> out;
  for (const auto& p : impl_->programs) {
    if (!p->robot) continue;
    const std::string r = "task." + p->config.robot + ".";
    for (const char* c : {"line", "tool.x", "tool.y", "tool.z"}) out.push_back(r + c);
  }
  return out;
}

bool Runtime::Impl::Resume(Program& p) {
  if (p.ended) return true;
  ArmBudget(p.co, config.instruction_budget);
  int results = 0;
  const int status = lua_resume(p.co, p.L, 0, &results);
  if (status == LUA_YIELD) {
    lua_pop(p.co, results);
    return true;
  }
  if (status == LUA_OK) {
    p.ended = true;
    lua_sethook(p.co, nullptr, 0, 0);
    return true;
  }
  // the message, then the coroutine's stack as it was at the error
  p.failed_line = std::max(1, WaitingLine(p.co));  // (the log's line column: not 0, which says "ended")
  const char* message = lua_tostring(p.co, -1);
  luaL_traceback(p.L, p.co, message ? message : "(error object is not a string)", 0);
  error = std::string(lua_tostring(p.L, -1)) + "\n(program of " + p.label + ", t = ";
  char t[32];
  std::snprintf(t, sizeof t, "%.6g s)", p.t_s);
  error += t;
  lua_pop(p.L, 1);
  p.ended = true;
  return false;
}

bool Runtime::Impl::SendCommands(Program& p) {
  std::string why;
  if (p.robot) {
    Robot& r = *p.robot;
    r.command[0] = 1.0;  // position mode
    for (std::size_t i = 0; i < r.arm_index.size(); ++i) r.command[1 + r.arm_index[i]] = r.q_ref[i];
    if (!r.arm->Write(r.command, &why)) {
      p.failed_line = std::max(1, WaitingLine(p.co));
      error = p.config.script + ": arm '" + r.arm->name() + "' refused the command: " + why;
      return false;
    }
  }
  for (const auto& [name, values] : p.device_commands) {
    if (!devices->Find(name)->Write(values, &why)) {
      p.failed_line = std::max(1, WaitingLine(p.co));
      error = p.config.script + ": device '" + name + "' refused the command: " + why;
      return false;
    }
  }
  return true;
}

bool Runtime::Step(double t_s, double* columns) {
  Impl& s = *impl_;
  if (!s.error.empty()) return false;
  if (!s.ResumeAll(t_s)) {
    s.WriteColumns(columns);  // the failed program's line column says where it died
    return false;
  }
  s.WriteColumns(columns);
  return true;
}

bool Runtime::Impl::ResumeAll(double t_s) {
  Impl& s = *this;
  for (auto& pp : s.programs) {
    Program& p = *pp;
    p.t_s = t_s;
    if (p.robot) {
      Robot& r = *p.robot;
      if (!r.arm->Read(&r.state)) {
        if (!r.started) continue;  // no state yet: nothing to start from
      } else {
        for (int i = 0; i < r.model->dof(); ++i) r.q_meas[i] = r.state[1 + r.arm_index[i]];
        if (!r.started) {
          r.q_ref = r.q_meas;
          for (int j = 0; j < r.arm_dof; ++j) r.command[1 + j] = r.state[1 + j];
          r.started = true;
        }
      }
    }
    if (!s.Resume(p)) return false;
    if (p.robot && s.board.stops.erase(p.config.robot)) StopMotion(p.robot.get(), p.period_s);
    if (p.robot) AdvanceMotion(p.robot.get());
    if (!s.SendCommands(p)) return false;
  }
  return true;
}

void Runtime::Impl::WriteColumns(double* columns) {
  if (columns) {
    for (auto& p : programs) {
      if (!p->robot) continue;
      Robot& r = *p->robot;
      *columns++ = p->failed_line > 0 ? p->failed_line : (p->ended ? 0 : WaitingLine(p->co));
      // the planned tool position: the plan's own sample, else forward kinematics once per change
      if (r.next > 0 && r.next <= r.plan.tool_W.size() && r.plan.q[r.next - 1] == r.q_ref) {
        r.tool_ref_W = r.plan.tool_W[r.next - 1].p;
        r.tool_ref_q = r.q_ref;
      } else if (r.tool_ref_q.size() != r.q_ref.size() || r.tool_ref_q != r.q_ref) {
        r.tool_ref_W = r.planner->ToolPose(r.q_ref).p;
        r.tool_ref_q = r.q_ref;
      }
      for (int i = 0; i < 3; ++i) *columns++ = r.tool_ref_W[i];
    }
  }
}

bool Runtime::finished() const {
  return std::all_of(impl_->programs.begin(), impl_->programs.end(), [](const auto& p) { return p->ended; });
}

const std::string& Runtime::error() const { return impl_->error; }

}  // namespace vlab::task
