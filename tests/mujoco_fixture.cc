#include "mujoco_fixture.h"

#include <cctype>
#include <utility>

namespace vlab::test {

namespace {

// the fixed start of warning i's text: mju_warningText up to its first number
std::string TextPrefix(int warning_index) {
  const std::string text = mju_warningText(warning_index, 0);
  std::size_t end = 0;
  while (end < text.size() && !std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
  return text.substr(0, end);
}

std::string KnownNames() {
  std::string names;
  for (int i = 0; i < mjNWARNING; ++i) names += std::string(i ? ", " : "") + WarningName(i);
  return names;
}

}  // namespace

std::string SourcePath(const std::string& path) {
  if (!path.empty() && path.front() == '/') return path;
  return std::string(VLAB_SOURCE_DIR) + "/" + path;
}

bool AnyWarning(const mjData& data) {
  for (int i = 0; i < mjNWARNING; ++i) {
    if (data.warning[i].number > 0) return true;
  }
  return false;
}

int WarningIndexOfText(const std::string& text) {
  for (int i = 0; i < mjNWARNING; ++i) {
    if (text.rfind(TextPrefix(i), 0) == 0) return i;
  }
  return -1;
}

MujocoTest::MujocoTest() {
  InstallMujocoHandlers();
  // texts left by a test without this fixture are not this test's
  TakeMujocoWarningTexts();
}

void MujocoTest::TearDown() {
  // texts by warning; a text that is none of mjData's warnings cannot be allowed
  std::array<std::vector<std::string>, mjNWARNING> texts;
  for (std::string& text : TakeMujocoWarningTexts()) {
    const int i = WarningIndexOfText(text);
    if (i < 0) {
      ADD_FAILURE() << "MuJoCo warning (not one of mjData's, so it cannot be allowed): " << text;
    } else {
      texts[i].push_back(std::move(text));
    }
  }
  // counters of the data the fixture made or watches
  std::array<long, mjNWARNING> counted{};
  std::vector<const mjData*> all(watched_);
  for (const DataPtr& data : data_) all.push_back(data.get());
  for (const mjData* data : all) {
    for (int i = 0; i < mjNWARNING; ++i) counted[i] += data->warning[i].number;
  }
  // one failure per undeclared warning, with what saw it
  for (int i = 0; i < mjNWARNING; ++i) {
    if (allowed_.count(i) || (texts[i].empty() && counted[i] == 0 && first_step_counts_[i] == 0)) continue;
    std::vector<std::string> seen;
    if (!texts[i].empty()) {
      const std::size_t more = texts[i].size() - 1;
      seen.push_back(texts[i].front() + (more ? " (and " + std::to_string(more) + " more texts)" : ""));
    }
    if (counted[i] > 0) seen.push_back("mjData::warning counts " + std::to_string(counted[i]));
    if (first_step_counts_[i] > 0) seen.push_back("raised by a loaded model's first step (MuJoCo's compiler warning)");
    std::string why;
    for (const std::string& s : seen) why += (why.empty() ? "" : "; ") + s;
    ADD_FAILURE() << "MuJoCo warning '" << WarningName(i) << "' not declared with AllowWarning(\"" << WarningName(i)
                  << "\"): " << why;
  }
}

void MujocoTest::AllowWarning(const std::string& name) {
  const int i = WarningIndex(name);
  if (i < 0) {
    ADD_FAILURE() << "AllowWarning: no MuJoCo warning '" << name << "' (known: " << KnownNames() << ")";
    return;
  }
  allowed_.insert(i);
}

mjModel* MujocoTest::LoadModel(const std::string& path) {
  models_.push_back(vlab::LoadModel(SourcePath(path)));
  CountFirstStep(models_.back().get());
  return models_.back().get();
}

mjModel* MujocoTest::LoadModelFromString(const std::string& name, const std::string& xml) {
  models_.push_back(vlab::LoadModelFromString(name, xml));
  CountFirstStep(models_.back().get());
  return models_.back().get();
}

mjData* MujocoTest::MakeData(const mjModel* model) {
  data_.push_back(vlab::MakeData(model));
  return data_.back().get();
}

void MujocoTest::WatchData(const mjData* data) { watched_.push_back(data); }

void MujocoTest::CountFirstStep(const mjModel* model) {
  const DataPtr scratch = vlab::MakeData(model);
  mj_resetData(model, scratch.get());
  mj_step(model, scratch.get());
  for (int i = 0; i < mjNWARNING; ++i) first_step_counts_[i] += scratch->warning[i].number;
}

}  // namespace vlab::test
