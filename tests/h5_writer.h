// Writes small HDF5 fixtures for the reader tests straight with the HDF5 C library, so that the
// fixtures do not depend on the code under test.
#pragma once

#include <hdf5.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace h5w {

class Writer {
public:
  /// `latestFormat`: the newest file format (version 2 object headers, links stored in them or
  /// in fractal heaps) instead of the default (symbol tables: B-trees and local heaps).
  explicit Writer(const std::string& path, bool latestFormat = false) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    const hid_t access = H5Pcreate(H5P_FILE_ACCESS);
    if (latestFormat) H5Pset_libver_bounds(access, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
    file_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, access);
    H5Pclose(access);
    if (file_ < 0) throw std::runtime_error("cannot create " + path);
  }
  ~Writer() { H5Fclose(file_); }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void group(const std::string& path) {
    H5Gclose(check(H5Gcreate2(file_, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT)));
  }

  /// A dataset of `fileType` from memory of `memType` (dims outermost first).
  void dataset(const std::string& path, hid_t memType, hid_t fileType, const std::vector<hsize_t>& dims,
               const void* data) {
    const hid_t space = H5Screate_simple(int(dims.size()), dims.data(), nullptr);
    const hid_t d = check(H5Dcreate2(file_, path.c_str(), fileType, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (H5Dwrite(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) throw std::runtime_error("write " + path);
    H5Dclose(d);
    H5Sclose(space);
  }
  void doubles(const std::string& path, const std::vector<hsize_t>& dims, const std::vector<double>& v,
               bool asFloat = false) {
    dataset(path, H5T_NATIVE_DOUBLE, asFloat ? H5T_IEEE_F32LE : H5T_IEEE_F64LE, dims, v.data());
  }
  void ints(const std::string& path, const std::vector<hsize_t>& dims, const std::vector<int>& v) {
    dataset(path, H5T_NATIVE_INT, H5T_STD_I32LE, dims, v.data());
  }
  void int64s(const std::string& path, const std::vector<hsize_t>& dims, const std::vector<long long>& v) {
    dataset(path, H5T_NATIVE_LLONG, H5T_STD_I64LE, dims, v.data());
  }
  /// Fixed-length strings of `size` characters, space padded.
  void strings(const std::string& path, const std::vector<hsize_t>& dims, const std::vector<std::string>& v,
               size_t size) {
    std::string buf;
    for (const std::string& s : v)
      buf += (s + std::string(size, ' ')).substr(0, size);
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, size);
    H5Tset_strpad(t, H5T_STR_SPACEPAD);
    dataset(path, t, t, dims, buf.data());
    H5Tclose(t);
  }
  /// A compound of int members, one record per `members.size()` values.
  void intCompound(const std::string& path, const std::vector<std::string>& members, const std::vector<int>& v) {
    const hid_t t = intCompoundType(members);
    const hsize_t n = v.size() / members.size();
    dataset(path, t, t, {n}, v.data());
    H5Tclose(t);
  }
  /// FLASH-style (name S80, value) tables.
  void nameValueTable(const std::string& path, const std::vector<std::string>& names, const std::vector<double>& values,
                      bool integer) {
    const size_t valueSize = integer ? sizeof(int) : sizeof(double);
    const size_t rec = 80 + valueSize;
    std::vector<unsigned char> buf(rec * names.size(), 0);
    for (size_t i = 0; i < names.size(); ++i) {
      std::string n = (names[i] + std::string(80, ' ')).substr(0, 80);
      std::copy(n.begin(), n.end(), buf.begin() + long(i * rec));
      if (integer) {
        const int v = int(values[i]);
        std::memcpy(&buf[i * rec + 80], &v, sizeof v);
      } else {
        std::memcpy(&buf[i * rec + 80], &values[i], sizeof(double));
      }
    }
    const hid_t s = H5Tcopy(H5T_C_S1);
    H5Tset_size(s, 80);
    H5Tset_strpad(s, H5T_STR_SPACEPAD);
    const hid_t t = H5Tcreate(H5T_COMPOUND, rec);
    H5Tinsert(t, "name", 0, s);
    H5Tinsert(t, "value", 80, integer ? H5T_NATIVE_INT : H5T_NATIVE_DOUBLE);
    dataset(path, t, t, {hsize_t(names.size())}, buf.data());
    H5Tclose(t);
    H5Tclose(s);
  }

  void attrInts(const std::string& obj, const std::string& name, const std::vector<int>& v) {
    attr(obj, name, H5T_NATIVE_INT, H5T_STD_I32LE, v.size(), v.data());
  }
  void attrDoubles(const std::string& obj, const std::string& name, const std::vector<double>& v) {
    attr(obj, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, v.size(), v.data());
  }
  void attrString(const std::string& obj, const std::string& name, const std::string& v) {
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, v.size() + 1);
    attr(obj, name, t, t, 1, v.c_str());
    H5Tclose(t);
  }
  void attrIntCompound(const std::string& obj, const std::string& name, const std::vector<std::string>& members,
                       const std::vector<int>& v) {
    const hid_t t = intCompoundType(members);
    attr(obj, name, t, t, 1, v.data());
    H5Tclose(t);
  }

private:
  static hid_t check(hid_t id) {
    if (id < 0) throw std::runtime_error("HDF5 fixture write failed");
    return id;
  }
  static hid_t intCompoundType(const std::vector<std::string>& members) {
    const hid_t t = H5Tcreate(H5T_COMPOUND, members.size() * sizeof(int));
    for (size_t i = 0; i < members.size(); ++i)
      H5Tinsert(t, members[i].c_str(), i * sizeof(int), H5T_NATIVE_INT);
    return t;
  }
  void attr(const std::string& obj, const std::string& name, hid_t memType, hid_t fileType, size_t n,
            const void* data) {
    const hid_t o = check(H5Oopen(file_, obj.c_str(), H5P_DEFAULT));
    const hsize_t dims[1] = {n};
    const hid_t space = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, dims, nullptr);
    const hid_t a = check(H5Acreate2(o, name.c_str(), fileType, space, H5P_DEFAULT, H5P_DEFAULT));
    H5Awrite(a, memType, data);
    H5Aclose(a);
    H5Sclose(space);
    H5Oclose(o);
  }
  hid_t file_ = -1;
};

} // namespace h5w
