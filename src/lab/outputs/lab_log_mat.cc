#include "lab/outputs/lab_log_mat.h"

#include <matio.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "lab/outputs/lab_log_formats.h"

namespace vlab::lab {

namespace {

// a char matrix of one row per string, padded with blanks (cellstr() makes it a cell array)
matvar_t* CharRows(const char* name, const std::vector<std::string>& values) {
  std::size_t width = 0;
  for (const std::string& v : values) width = std::max(width, v.size());
  std::vector<char> text(values.size() * width, ' ');  // column-major
  for (std::size_t r = 0; r < values.size(); ++r) {
    for (std::size_t c = 0; c < values[r].size(); ++c) text[c * values.size() + r] = values[r][c];
  }
  std::size_t dims[2] = {values.size(), width};
  return Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UTF8, 2, dims, text.data(), 0);
}

class MatSink : public LogSink {
 public:
  MatSink(std::FILE* rows, std::string rows_path, std::string path, std::vector<std::string> columns)
      : rows_(rows), rows_path_(std::move(rows_path)), path_(std::move(path)), columns_(std::move(columns)) {}
  ~MatSink() override {
    if (rows_) std::fclose(rows_);
    ::unlink(rows_path_.c_str());
  }

  std::string Write(const double* rows, int count) override {
    const std::size_t n = static_cast<std::size_t>(count) * columns_.size();
    errno = 0;
    if (std::fwrite(rows, sizeof(double), n, rows_) != n || std::fflush(rows_) != 0) {
      return "log '" + path_ + "': write failed: " + std::strerror(errno ? errno : EIO);
    }
    count_ += count;
    return "";
  }

  std::string Close() override {
    if (!rows_) return "";
    std::string why = BuildMat();
    std::fclose(rows_);
    rows_ = nullptr;
    ::unlink(rows_path_.c_str());
    return why;
  }

 private:
  // one group's columns, column-major, read back from the rows file
  bool ReadGroup(const std::vector<int>& group, std::vector<double>* data) {
    const std::size_t n = columns_.size();
    data->assign(static_cast<std::size_t>(count_) * group.size(), 0.0);
    if (std::fseek(rows_, 0, SEEK_SET) != 0) return false;
    std::vector<double> block(static_cast<std::size_t>(RunLog::kRowsPerBlock) * n);
    for (long r0 = 0; r0 < count_; r0 += RunLog::kRowsPerBlock) {
      const long rows = std::min<long>(RunLog::kRowsPerBlock, count_ - r0);
      if (std::fread(block.data(), sizeof(double) * n, rows, rows_) != static_cast<std::size_t>(rows)) return false;
      for (long r = 0; r < rows; ++r) {
        for (std::size_t g = 0; g < group.size(); ++g) (*data)[g * count_ + r0 + r] = block[r * n + group[g]];
      }
    }
    return true;
  }

  std::string BuildMat() {
    const auto fail = [this](const std::string& what) { return "log '" + path_ + "': write failed: " + what; };
    mat_t* mat = Mat_CreateVer(path_.c_str(), nullptr, MAT_FT_MAT5);
    if (!mat) return fail("cannot create the file");
    std::string why;
    std::set<std::string> taken;
    std::vector<double> data;
    for (const ColumnGroupIndex& group : GroupColumns(columns_)) {
      // a unique variable name per group (two groups may sanitise alike)
      std::string name = MatVariableName(group.name);
      for (int k = 2; taken.count(name); ++k) name = MatVariableName(group.name) + "_" + std::to_string(k);
      taken.insert(name);
      if (!ReadGroup(group.columns, &data)) {
        why = fail("cannot read back its rows file '" + rows_path_ + "'");
        break;
      }
      std::vector<std::string> names, units;
      for (int c : group.columns) {
        names.push_back(columns_[c]);
        units.push_back(ColumnUnit(columns_[c]));
      }
      const char* fields[] = {"data", "names", "units"};
      std::size_t one[2] = {1, 1};
      std::size_t dims[2] = {static_cast<std::size_t>(count_), group.columns.size()};
      matvar_t* s = Mat_VarCreateStruct(name.c_str(), 2, one, fields, 3);
      matvar_t* d = Mat_VarCreate("data", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, data.data(), 0);
      matvar_t* n = CharRows("names", names);
      matvar_t* u = CharRows("units", units);
      bool ok = s && d && n && u;
      if (ok) {
        Mat_VarSetStructFieldByName(s, "data", 0, d);
        Mat_VarSetStructFieldByName(s, "names", 0, n);
        Mat_VarSetStructFieldByName(s, "units", 0, u);
        ok = Mat_VarWrite(mat, s, MAT_COMPRESSION_ZLIB) == 0;
        Mat_VarFree(s);
      } else {
        for (matvar_t* v : {s, d, n, u}) {
          if (v) Mat_VarFree(v);
        }
      }
      if (!ok) {
        why = fail("cannot write variable '" + name + "'");
        break;
      }
    }
    if (Mat_Close(mat) != 0 && why.empty()) why = fail("cannot close the file");
    return why;
  }

  std::FILE* rows_;
  std::string rows_path_;
  std::string path_;
  std::vector<std::string> columns_;
  long count_ = 0;
};

}  // namespace

std::string MatFileVersion() { return "5 (compressed)"; }

std::string MatVariableName(const std::string& group) {
  std::string name;
  for (char c : group) name.push_back(std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '_');
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) name = "v" + name;
  return name.substr(0, 63);
}

std::unique_ptr<LogSink> OpenMatSink(const std::string& path, const std::vector<std::string>& columns) {
  const std::filesystem::path p(path);
  const std::string rows_path = (p.parent_path() / ("." + p.filename().string() + ".rows")).string();
  std::FILE* rows = std::fopen(rows_path.c_str(), "w+be");
  if (!rows) throw std::runtime_error("log '" + path + "': cannot create '" + rows_path + "': " + std::strerror(errno));
  return std::make_unique<MatSink>(rows, rows_path, path, columns);
}

}  // namespace vlab::lab
