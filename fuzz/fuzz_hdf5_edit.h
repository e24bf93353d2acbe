// Rewrites of HDF5 attributes and datasets for the structure-aware HDF5 fuzz targets: the file
// stays well-formed HDF5 while its content becomes hostile.
#pragma once

#include "exabricks/amr/cells.h"
#include "exabricks/core/error.h"

#include <hdf5.h>

#include <string>

namespace fuzz {

/// Replaces (or adds) attribute `name` of `object` with `n` values of `type`.
inline void setAttr(hid_t file, const std::string& object, const std::string& name, hid_t type, const void* value,
                    hsize_t n) {
  const hid_t o = H5Oopen(file, object.c_str(), H5P_DEFAULT);
  if (o < 0) return;
  H5Adelete(o, name.c_str());
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t a = H5Acreate2(o, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  if (a >= 0) {
    H5Awrite(a, type, value);
    H5Aclose(a);
  }
  H5Sclose(space);
  H5Oclose(o);
}

/// Replaces (or adds) a one-dimensional dataset of `n` values of `type`.
inline void setDataset(hid_t file, const std::string& path, hid_t type, const void* values, hsize_t n) {
  H5Ldelete(file, path.c_str(), H5P_DEFAULT);
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t d = H5Dcreate2(file, path.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (d >= 0) {
    if (n) H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values);
    H5Dclose(d);
  }
  H5Sclose(space);
}

/// Closes the edited file and reads it as the reader does: field list, then every cell; a reader
/// may refuse it (exa::Error) but never crash, and what it returns is consistent.
template <typename List, typename Read> void closeAndRead(hid_t file, const std::string& path, List list, Read read) {
  H5Fclose(file);
  try {
    list(path);
    const exa::CellSet s = read(path);
    if (!s.fields.empty() && s.fields[0].values.size() != s.cells.size()) __builtin_trap();
  } catch (const exa::Error&) {
  }
}

} // namespace fuzz
