#include "lab/outputs/lab_log_hdf5.h"

#include <hdf5.h>

#include <cstring>
#include <stdexcept>

#include "core/core_errors.h"
#include "lab/outputs/lab_log_formats.h"

namespace vlab::lab {

namespace {

// an hid_t closed by its own close function when it goes out of scope
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// HDF5 prints its error stack on stderr by default: vlab reports its own one line
void QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// a string array attribute `name` on `object`
bool WriteStrings(hid_t object, const char* name, const std::vector<std::string>& values) {
  std::vector<const char*> pointers;
  for (const std::string& v : values) pointers.push_back(v.c_str());
  const hsize_t n = values.size();
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.ok() || H5Tset_size(type.get(), H5T_VARIABLE) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0)
    return false;
  Handle space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  Handle attribute(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  return attribute.ok() && H5Awrite(attribute.get(), type.get(), pointers.data()) >= 0;
}

class Hdf5Sink : public LogSink {
 public:
  Hdf5Sink(hid_t file, hid_t dataset, std::string path, std::size_t columns)
      : file_(file), dataset_(dataset), path_(std::move(path)), n_(columns) {
    pending_.reserve(static_cast<std::size_t>(kHdf5ChunkRows) * n_);
  }
  ~Hdf5Sink() override { Close(); }

  std::string Write(const double* rows, int count) override {
    // whole chunks only: a chunk is compressed once, never rewritten
    pending_.insert(pending_.end(), rows, rows + static_cast<std::size_t>(count) * n_);
    if (pending_.size() < static_cast<std::size_t>(kHdf5ChunkRows) * n_) return "";
    return WritePending();
  }

  std::string Close() override {
    if (file_ < 0) return "";
    std::string why = pending_.empty() ? "" : WritePending();
    H5Dclose(dataset_);
    if (H5Fclose(file_) < 0 && why.empty()) why = Error("cannot close the file");
    file_ = -1;
    return why;
  }

 private:
  std::string Error(const std::string& what) const { return "log '" + path_ + "': write failed: " + what; }

  std::string WritePending() {
    if (n_ == 0) return "";
    const hsize_t count[2] = {pending_.size() / n_, n_};
    const hsize_t start[2] = {rows_, 0};
    const hsize_t size[2] = {rows_ + count[0], n_};
    if (H5Dset_extent(dataset_, size) < 0) return Error("cannot extend /log");
    Handle file_space(H5Dget_space(dataset_), H5Sclose);
    Handle memory_space(H5Screate_simple(2, count, nullptr), H5Sclose);
    if (!file_space.ok() || H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
        H5Dwrite(dataset_, H5T_NATIVE_DOUBLE, memory_space.get(), file_space.get(), H5P_DEFAULT, pending_.data()) < 0) {
      return Error("cannot write rows " + std::to_string(rows_) + " on");
    }
    pending_.clear();
    rows_ += count[0];
    // on disk now: a run cut short keeps a valid file up to here
    if (H5Fflush(file_, H5F_SCOPE_GLOBAL) < 0) return Error("cannot flush (disk full?)");
    return "";
  }

  hid_t file_;
  hid_t dataset_;
  std::string path_;
  std::size_t n_;
  hsize_t rows_ = 0;
  std::vector<double> pending_;
};

}  // namespace

std::unique_ptr<LogSink> OpenHdf5Sink(const std::string& path, const std::vector<std::string>& columns) {
  QuietHdf5();
  const auto fail = [&](const std::string& what) { return std::runtime_error("log '" + path + "': " + what); };
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw fail("cannot create the HDF5 file");
  // rows x columns, unlimited rows, chunks of one column, shuffled and deflated
  const hsize_t n = columns.size();
  const hsize_t initial[2] = {0, n};
  const hsize_t maximum[2] = {H5S_UNLIMITED, n};
  const hsize_t chunk[2] = {static_cast<hsize_t>(kHdf5ChunkRows), 1};
  Handle space(H5Screate_simple(2, initial, maximum), H5Sclose);
  Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  const bool set = n > 0 && H5Pset_chunk(properties.get(), 2, chunk) >= 0 && H5Pset_shuffle(properties.get()) >= 0 &&
                   H5Pset_deflate(properties.get(), 6) >= 0;
  const hid_t dataset =
      set ? H5Dcreate2(file, "log", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, properties.get(), H5P_DEFAULT) : -1;
  std::vector<std::string> units;
  for (const std::string& c : columns) units.push_back(ColumnUnit(c));
  if (dataset < 0 || !WriteStrings(dataset, "columns", columns) || !WriteStrings(dataset, "units", units)) {
    if (dataset >= 0) H5Dclose(dataset);
    H5Fclose(file);
    throw fail(n == 0 ? "no columns to log" : "cannot create the dataset /log");
  }
  return std::make_unique<Hdf5Sink>(file, dataset, path, columns.size());
}

scene::CsvTable ReadHdf5Log(const std::string& path) {
  QuietHdf5();
  const auto fail = [&](const std::string& what) { return InputError("HDF5 log '" + path + "': " + what); };
  if (H5Fis_hdf5(path.c_str()) <= 0) throw fail("not an HDF5 file");
  Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw fail("cannot open");
  Handle dataset(H5Dopen2(file.get(), "log", H5P_DEFAULT), H5Dclose);
  if (!dataset.ok()) throw fail("no dataset /log");
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  hsize_t dims[2] = {0, 0};
  if (H5Sget_simple_extent_ndims(space.get()) != 2 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) {
    throw fail("/log is not a matrix (rows x columns)");
  }
  scene::CsvTable t;
  t.file = path;
  // the column names: a string array attribute of one name per column
  Handle attribute(H5Aopen(dataset.get(), "columns", H5P_DEFAULT), H5Aclose);
  Handle attribute_space(attribute.ok() ? H5Aget_space(attribute.get()) : -1, H5Sclose);
  if (!attribute_space.ok() || H5Sget_simple_extent_npoints(attribute_space.get()) != static_cast<hssize_t>(dims[1])) {
    throw fail("/log has no attribute 'columns' with one name per column");
  }
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(type.get(), H5T_VARIABLE);
  H5Tset_cset(type.get(), H5T_CSET_UTF8);
  std::vector<char*> names(dims[1], nullptr);
  if (H5Aread(attribute.get(), type.get(), names.data()) < 0) throw fail("/log: 'columns' is not a string array");
  for (char* name : names) t.columns.push_back(name ? name : "");
  H5Dvlen_reclaim(type.get(), attribute_space.get(), H5P_DEFAULT, names.data());
  std::vector<double> data(dims[0] * dims[1]);
  if (!data.empty() && H5Dread(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) < 0) {
    throw fail("cannot read /log as float64");
  }
  for (hsize_t r = 0; r < dims[0]; ++r) {
    t.rows.emplace_back(data.begin() + r * dims[1], data.begin() + (r + 1) * dims[1]);
  }
  return t;
}

}  // namespace vlab::lab
