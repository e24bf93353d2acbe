#include "hdf5_file.h"

#include "exabricks/io/hdf5.h"

#include "exabricks/core/error.h"

#include "checked.h"

#include <algorithm>
#include <cstring>
#include <fstream>

namespace exa::h5 {
namespace {

// Nothing the readers ask for is larger; a corrupt header must not make us allocate terabytes.
constexpr uint64_t kMaxElements = uint64_t(1) << 33;
// Longest fixed-length string (dataset element, attribute or compound member) that is read.
constexpr size_t kMaxStringBytes = size_t(1) << 16;

/// Variable-length strings read by libhdf5, released however the reading ends.
struct VlenStrings {
  hid_t memType, space;
  std::vector<char*> ptrs;
  ~VlenStrings() {
    if (std::any_of(ptrs.begin(), ptrs.end(), [](char* p) { return p != nullptr; }))
      H5Dvlen_reclaim(memType, space, H5P_DEFAULT, ptrs.data());
  }
};

void silence() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  return s;
}

bool isNumeric(hid_t type) {
  const H5T_class_t c = H5Tget_class(type);
  return c == H5T_INTEGER || c == H5T_FLOAT;
}

/// A memory compound with the file compound's member names: numbers as double, fixed strings
/// as NUL-terminated char arrays. Returns the type, fills the layout.
struct CompoundLayout {
  Id type;
  std::vector<size_t> offsets;
  std::vector<size_t> stringSizes; ///< 0 for numeric members
  std::vector<std::string> names;
  size_t size = 0;
};

bool compoundLayout(hid_t fileType, CompoundLayout& out, std::string& problem) {
  const int n = H5Tget_nmembers(fileType);
  if (n <= 0) {
    problem = "empty compound type";
    return false;
  }
  for (int i = 0; i < n; ++i) {
    char* name = H5Tget_member_name(fileType, unsigned(i));
    out.names.push_back(name ? name : "");
    H5free_memory(name);
    Id mt(H5Tget_member_type(fileType, unsigned(i)), H5Tclose);
    out.offsets.push_back(out.size);
    if (isNumeric(mt.get())) {
      out.stringSizes.push_back(0);
      out.size += sizeof(double);
    } else if (H5Tget_class(mt.get()) == H5T_STRING && !H5Tis_variable_str(mt.get())) {
      if (H5Tget_size(mt.get()) > kMaxStringBytes) {
        problem = "compound member '" + out.names.back() + "' is a string of more than 65536 bytes";
        return false;
      }
      const size_t s = H5Tget_size(mt.get()) + 1;
      out.stringSizes.push_back(s);
      out.size += s;
    } else {
      problem = "compound member '" + out.names.back() + "' is neither a number nor a fixed-length string";
      return false;
    }
  }
  out.type = Id(H5Tcreate(H5T_COMPOUND, out.size), H5Tclose);
  for (int i = 0; i < n; ++i) {
    if (out.stringSizes[size_t(i)] == 0) {
      H5Tinsert(out.type.get(), out.names[size_t(i)].c_str(), out.offsets[size_t(i)], H5T_NATIVE_DOUBLE);
    } else {
      Id st(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(st.get(), out.stringSizes[size_t(i)]);
      H5Tset_strpad(st.get(), H5T_STR_NULLTERM);
      H5Tinsert(out.type.get(), out.names[size_t(i)].c_str(), out.offsets[size_t(i)], st.get());
    }
  }
  return true;
}

uint64_t elementCount(hid_t space) {
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  return n < 0 ? 0 : uint64_t(n);
}

/// Checks what a dataset declares against what it stores before anything is allocated for it:
/// its storage must lie within the file, and hold every element (uncompressed) or at least
/// 1/kMaxInflate of their bytes (filtered).
void checkStorage(const File& f, hid_t file, hid_t d, uint64_t elements, const std::string& name) {
  Id type(H5Dget_type(d), H5Tclose);
  const size_t elementBytes = H5Tget_size(type.get());
  if (elementBytes == 0) f.bad(name, "cannot read the element type");
  hsize_t fileBytes = 0;
  if (H5Fget_filesize(file, &fileBytes) < 0) f.bad(name, "cannot read the file size");
  const uint64_t stored = H5Dget_storage_size(d);
  if (stored > fileBytes)
    f.bad(name, strCat("declares ", stored, " bytes of storage in a file of ", fileBytes, " bytes (corrupt file?)"));
  Id plist(H5Dget_create_plist(d), H5Pclose);
  const int filters = plist ? H5Pget_nfilters(plist.get()) : 0;
  const std::string where = strCat(f.path(), ": ", name);
  if (filters <= 0) {
    io::requireBytes(elements, elementBytes, stored, where);
  } else {
    uint64_t bytes = 0, bound = 0;
    if (!io::productWithin(elements, elementBytes, UINT64_MAX, bytes) ||
        !io::productWithin(stored + 1, io::kMaxInflate, UINT64_MAX, bound) || bytes > bound)
      f.bad(name, strCat("declares ", elements, " values of ", elementBytes, " bytes, more than its ", stored,
                         " compressed bytes can hold"));
  }
}

} // namespace

bool hasSignature(const std::string& path) {
  static const char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  in.seekg(0, std::ios::end);
  const uint64_t size = uint64_t(in.tellg());
  for (uint64_t at = 0; at + 8 <= size; at = at == 0 ? 512 : at * 2) {
    char buf[8];
    in.seekg(std::streamoff(at));
    if (!in.read(buf, 8)) return false;
    if (std::memcmp(buf, kSignature, 8) == 0) return true;
  }
  return false;
}

File::File(const std::string& path) : path_(path) {
  silence();
  if (!hasSignature(path)) {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) fail(path, ": cannot open (missing file?)");
    fail(path, ": not an HDF5 file (no HDF5 signature)");
  }
  // Closing the file closes whatever objects an error path might have left open.
  Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (access) H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
  file_ = Id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access ? access.get() : H5P_DEFAULT), H5Fclose);
  if (!file_) fail(path, ": cannot open as HDF5 (corrupt or truncated file?)");
}

void File::bad(const std::string& object, const std::string& what) const { fail(path_, ": ", object, ": ", what); }

bool File::exists(const std::string& object) const {
  // H5Lexists needs every parent to exist, so walk the path one link at a time.
  std::string partial;
  size_t pos = 0;
  while (pos <= object.size()) {
    size_t next = object.find('/', pos);
    if (next == std::string::npos) next = object.size();
    const std::string part = object.substr(pos, next - pos);
    if (!part.empty()) {
      partial += "/" + part;
      if (H5Lexists(file_.get(), partial.c_str(), H5P_DEFAULT) <= 0) return false;
    }
    pos = next + 1;
  }
  return true;
}

Id File::openObject(const std::string& object) const {
  if (!exists(object)) bad(object, "missing");
  Id id(H5Oopen(file_.get(), object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!id) bad(object, "cannot open (corrupt file?)");
  return id;
}

Id File::openDataset(const std::string& dataset) const {
  if (!exists(dataset)) bad(dataset, "missing dataset");
  Id id(H5Dopen2(file_.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!id) bad(dataset, "cannot open as a dataset");
  return id;
}

std::vector<std::string> File::members(const std::string& group) const {
  Id g(H5Gopen2(file_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g) bad(group, "missing group");
  H5G_info_t info;
  if (H5Gget_info(g.get(), &info) < 0) bad(group, "cannot read the group");
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len = H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) bad(group, "cannot read a member name");
    std::string name(size_t(len) + 1, '\0');
    H5Lget_name_by_idx(g.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(), H5P_DEFAULT);
    name.resize(size_t(len));
    names.push_back(name);
  }
  return names;
}

bool File::isDataset(const std::string& object) const {
  if (!exists(object)) return false;
  H5O_info_t info;
  if (H5Oget_info_by_name(file_.get(), object.c_str(), &info, H5P_DEFAULT) < 0) return false;
  return info.type == H5O_TYPE_DATASET;
}

std::vector<uint64_t> File::dims(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  Id space(H5Dget_space(d.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) bad(dataset, "cannot read the dataspace");
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<uint64_t>(dims.begin(), dims.end());
}

void File::requireStorage(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  Id space(H5Dget_space(d.get()), H5Sclose);
  checkStorage(*this, file_.get(), d.get(), elementCount(space.get()), dataset);
}

bool File::isDouble(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  return H5Tget_class(type.get()) == H5T_FLOAT && H5Tget_size(type.get()) > 4;
}

namespace {
template <typename T>
std::vector<T> readNumeric(const File& f, hid_t file, hid_t d, hid_t memType, const std::string& name) {
  Id type(H5Dget_type(d), H5Tclose);
  if (!isNumeric(type.get())) f.bad(name, "not a numeric dataset");
  Id space(H5Dget_space(d), H5Sclose);
  const uint64_t n = elementCount(space.get());
  if (n > kMaxElements) f.bad(name, "dataset too large");
  checkStorage(f, file, d, n, name);
  std::vector<T> out = io::allocate<T>(n, [&] { return strCat(f.path(), ": ", name); });
  if (n && H5Dread(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    f.bad(name, "cannot read (truncated or corrupt file?)");
  return out;
}
} // namespace

std::vector<double> File::readDoubles(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  return readNumeric<double>(*this, file_.get(), d.get(), H5T_NATIVE_DOUBLE, dataset);
}

std::vector<int64_t> File::readInts(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  return readNumeric<int64_t>(*this, file_.get(), d.get(), H5T_NATIVE_INT64, dataset);
}

std::vector<double> File::readRows(const std::string& dataset, uint64_t first, uint64_t count) const {
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  if (!isNumeric(type.get())) bad(dataset, "not a numeric dataset");
  Id space(H5Dget_space(d.get()), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 1) bad(dataset, "has no dimensions");
  std::vector<hsize_t> dims(static_cast<size_t>(rank)), start(size_t(rank), 0), cnt;
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  if (first + count > dims[0] || first + count < first)
    bad(dataset, strCat("rows ", first, "..", first + count, " requested of ", dims[0]));
  cnt = dims;
  cnt[0] = count;
  start[0] = first;
  uint64_t n = 1;
  for (hsize_t c : cnt) n *= c;
  if (n > kMaxElements) bad(dataset, "dataset too large");
  checkStorage(*this, file_.get(), d.get(), elementCount(space.get()), dataset);
  std::vector<double> out = io::allocate<double>(n, [&] { return strCat(path_, ": ", dataset); });
  if (n == 0) return out;
  if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, cnt.data(), nullptr) < 0)
    bad(dataset, "cannot select rows");
  Id mem(H5Screate_simple(rank, cnt.data(), nullptr), H5Sclose);
  if (H5Dread(d.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, out.data()) < 0)
    bad(dataset, strCat("cannot read rows ", first, "..", first + count, " (truncated or corrupt file?)"));
  return out;
}

std::vector<std::string> File::readStrings(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING) bad(dataset, "not a string dataset");
  Id space(H5Dget_space(d.get()), H5Sclose);
  const uint64_t n = elementCount(space.get());
  if (n > (uint64_t(1) << 24)) bad(dataset, "too many strings");
  checkStorage(*this, file_.get(), d.get(), n, dataset);
  std::vector<std::string> out;
  if (H5Tis_variable_str(type.get())) {
    Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mt.get(), H5T_VARIABLE);
    VlenStrings strings{mt.get(), space.get(), std::vector<char*>(static_cast<size_t>(n), nullptr)};
    if (n && H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.ptrs.data()) < 0)
      bad(dataset, "cannot read");
    for (char* p : strings.ptrs) out.push_back(trimmed(p ? std::string(p, strnlen(p, kMaxStringBytes)) : ""));
    return out;
  }
  const size_t size = H5Tget_size(type.get());
  if (size > kMaxStringBytes) bad(dataset, strCat("strings of ", size, " bytes (at most 65536 are read)"));
  Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mt.get(), size + 1);
  H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
  std::vector<char> buf(size_t(n) * (size + 1), '\0');
  if (n && H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0) bad(dataset, "cannot read");
  for (uint64_t i = 0; i < n; ++i) out.push_back(trimmed(std::string(buf.data() + i * (size + 1), size)));
  return out;
}

CompoundTable File::readCompound(const std::string& dataset) const {
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_COMPOUND) bad(dataset, "not a compound dataset");
  CompoundLayout layout;
  std::string problem;
  if (!compoundLayout(type.get(), layout, problem)) bad(dataset, problem);
  Id space(H5Dget_space(d.get()), H5Sclose);
  const uint64_t n = elementCount(space.get());
  if (n > kMaxElements || n * layout.size > (uint64_t(1) << 34)) bad(dataset, "dataset too large");
  checkStorage(*this, file_.get(), d.get(), n, dataset);
  std::vector<unsigned char> buf = io::allocate<unsigned char>(n * layout.size, [&] { return strCat(path_, ": ", dataset); });
  if (n && H5Dread(d.get(), layout.type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0)
    bad(dataset, "cannot read (truncated or corrupt file?)");
  CompoundTable t;
  t.members = layout.names;
  t.records = size_t(n);
  for (uint64_t r = 0; r < n; ++r) {
    const unsigned char* rec = buf.data() + r * layout.size;
    for (size_t m = 0; m < layout.names.size(); ++m) {
      if (layout.stringSizes[m] == 0) {
        double v;
        std::memcpy(&v, rec + layout.offsets[m], sizeof v);
        t.values.push_back(v);
      } else {
        const char* s = reinterpret_cast<const char*>(rec + layout.offsets[m]);
        t.strings.push_back(trimmed(std::string(s, strnlen(s, layout.stringSizes[m]))));
        t.values.push_back(0.0);
      }
    }
  }
  return t;
}

bool File::hasAttribute(const std::string& object, const std::string& name) const {
  if (!exists(object)) return false;
  return H5Aexists_by_name(file_.get(), object.c_str(), name.c_str(), H5P_DEFAULT) > 0;
}

Id File::openAttribute(const std::string& object, const std::string& name, Id& holder) const {
  holder = openObject(object);
  if (H5Aexists(holder.get(), name.c_str()) <= 0) bad(object, "missing attribute '" + name + "'");
  Id a(H5Aopen(holder.get(), name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a) bad(object, "cannot open attribute '" + name + "'");
  return a;
}

std::vector<double> File::attrNumbers(const std::string& object, const std::string& name) const {
  Id holder;
  const Id a = openAttribute(object, name, holder);
  Id type(H5Aget_type(a.get()), H5Tclose);
  Id space(H5Aget_space(a.get()), H5Sclose);
  const uint64_t n = elementCount(space.get());
  if (n > 4096) bad(object, "attribute '" + name + "' is too large");
  if (isNumeric(type.get())) {
    std::vector<double> out(static_cast<size_t>(n));
    if (n && H5Aread(a.get(), H5T_NATIVE_DOUBLE, out.data()) < 0) bad(object, "cannot read attribute '" + name + "'");
    return out;
  }
  if (H5Tget_class(type.get()) == H5T_COMPOUND) {
    CompoundLayout layout;
    std::string problem;
    if (!compoundLayout(type.get(), layout, problem)) bad(object, "attribute '" + name + "': " + problem);
    std::vector<unsigned char> buf(size_t(n) * layout.size);
    if (n && H5Aread(a.get(), layout.type.get(), buf.data()) < 0) bad(object, "cannot read attribute '" + name + "'");
    std::vector<double> out;
    for (uint64_t r = 0; r < n; ++r)
      for (size_t m = 0; m < layout.names.size(); ++m) {
        if (layout.stringSizes[m] != 0) bad(object, "attribute '" + name + "' holds strings, expected numbers");
        double v;
        std::memcpy(&v, buf.data() + r * layout.size + layout.offsets[m], sizeof v);
        out.push_back(v);
      }
    return out;
  }
  bad(object, "attribute '" + name + "' is not numeric");
}

std::string File::attrString(const std::string& object, const std::string& name) const {
  Id holder;
  const Id a = openAttribute(object, name, holder);
  Id type(H5Aget_type(a.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING) bad(object, "attribute '" + name + "' is not a string");
  Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
  Id space(H5Aget_space(a.get()), H5Sclose);
  if (elementCount(space.get()) != 1) bad(object, "attribute '" + name + "' is not a single string");
  if (H5Tis_variable_str(type.get())) {
    H5Tset_size(mt.get(), H5T_VARIABLE);
    VlenStrings strings{mt.get(), space.get(), std::vector<char*>(1, nullptr)};
    if (H5Aread(a.get(), mt.get(), strings.ptrs.data()) < 0) bad(object, "cannot read attribute '" + name + "'");
    const char* p = strings.ptrs[0];
    return trimmed(p ? std::string(p, strnlen(p, kMaxStringBytes)) : "");
  }
  const size_t size = H5Tget_size(type.get());
  if (size > kMaxStringBytes) bad(object, strCat("attribute '", name, "' is a string of ", size, " bytes (at most 65536 are read)"));
  H5Tset_size(mt.get(), size + 1);
  H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
  std::string buf(size + 1, '\0');
  if (H5Aread(a.get(), mt.get(), buf.data()) < 0) bad(object, "cannot read attribute '" + name + "'");
  return trimmed(std::string(buf.c_str()));
}

} // namespace exa::h5

namespace exa {
bool isHdf5File(const std::string& path) { return h5::hasSignature(path); }
} // namespace exa
