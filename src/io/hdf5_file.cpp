#include "hdf5_file.h"

#include "exabricks/core/error.h"

#include "checked.h"
#include "hdf5_checks.h"

#include <algorithm>
#include <cstring>
#include <fstream>

namespace exa::h5 {
using namespace detail;
namespace {

// Nothing the readers ask for is larger; a corrupt header must not make us allocate terabytes.
constexpr uint64_t kMaxElements = uint64_t(1) << 33;

/// Checks what a dataset declares against what it stores before anything is allocated for it:
/// its storage must lie within the file, and hold every element (uncompressed) or at least
/// 1/kMaxInflate of their bytes (filtered).
void checkStorage(const File& f, hid_t file, hid_t d, uint64_t elements, const std::string& name) {
  Id type(H5Dget_type(d), H5Tclose);
  std::string problem;
  if (!type || !typeIsSound(type.get(), problem))
    f.bad(name, problem.empty() ? "cannot read the element type" : problem);
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

/// The dataset's type and dataspace, checked before anything is read or converted.
void requireSound(const File& f, hid_t type, hid_t space, const std::string& name) {
  std::string problem;
  if (type < 0 || !typeIsSound(type, problem)) f.bad(name, problem.empty() ? "cannot read the element type" : problem);
  if (space < 0 || !spaceIsSound(space, problem)) f.bad(name, problem.empty() ? "cannot read the dataspace" : problem);
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
  const Lock lock(libraryLock());
  silence();
  if (!hasSignature(path)) {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) fail(path, ": cannot open (missing file?)");
    fail(path, ": not an HDF5 file (no HDF5 signature)");
  }
  checkInChild(path);
  // Closing the file closes whatever objects an error path might have left open.
  Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (access) H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
  file_ = Id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access ? access.get() : H5P_DEFAULT), H5Fclose);
  if (!file_) fail(path, ": cannot open as HDF5 (corrupt or truncated file?)");
}

File::~File() {
  const Lock lock(libraryLock());
  file_.reset();
}

void File::bad(const std::string& object, const std::string& what) const { fail(path_, ": ", object, ": ", what); }

const std::vector<std::string>& File::links(const std::string& group) const {
  auto it = links_.find(group);
  if (it == links_.end()) {
    std::vector<std::string> names;
    if (listLinks(file_.get(), group, names) == Listing::Failed)
      bad(group, "cannot list the group's members (damaged file?)");
    it = links_.emplace(group, std::move(names)).first;
  }
  return it->second;
}

const std::vector<std::string>& File::attributes(const std::string& object) const {
  auto it = attributes_.find(object);
  if (it == attributes_.end()) {
    const Id holder = openObject(object);
    std::vector<std::string> names;
    if (!listAttributes(holder.get(), names)) bad(object, "cannot list the attributes (corrupt file?)");
    it = attributes_.emplace(object, std::move(names)).first;
  }
  return it->second;
}

bool File::exists(const std::string& object) const {
  const Lock lock(libraryLock());
  // Each link on the path must be listed by its group: names are only ever looked up once a
  // listing has shown them.
  std::string group = "/";
  size_t pos = 0;
  while (pos <= object.size()) {
    size_t next = object.find('/', pos);
    if (next == std::string::npos) next = object.size();
    const std::string part = object.substr(pos, next - pos);
    if (!part.empty()) {
      const std::vector<std::string>& names = links(group);
      if (!std::binary_search(names.begin(), names.end(), part)) return false;
      group = group == "/" ? "/" + part : group + "/" + part;
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
  const Lock lock(libraryLock());
  if (!exists(group)) bad(group, "missing group");
  const Id g(H5Gopen2(file_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g) bad(group, "missing group");
  return links(group);
}

bool File::isDataset(const std::string& object) const {
  const Lock lock(libraryLock());
  if (!exists(object)) return false;
  H5O_info_t info;
  if (H5Oget_info_by_name(file_.get(), object.c_str(), &info, H5P_DEFAULT) < 0) return false;
  return info.type == H5O_TYPE_DATASET;
}

std::vector<uint64_t> File::dims(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id space(H5Dget_space(d.get()), H5Sclose);
  std::string problem;
  if (!space || !spaceIsSound(space.get(), problem))
    bad(dataset, problem.empty() ? "cannot read the dataspace" : problem);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) bad(dataset, "cannot read the dataspace");
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<uint64_t>(dims.begin(), dims.end());
}

void File::requireStorage(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id space(H5Dget_space(d.get()), H5Sclose);
  std::string problem;
  if (!space || !spaceIsSound(space.get(), problem))
    bad(dataset, problem.empty() ? "cannot read the dataspace" : problem);
  checkStorage(*this, file_.get(), d.get(), elementCount(space.get()), dataset);
}

bool File::isDouble(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  return H5Tget_class(type.get()) == H5T_FLOAT && H5Tget_size(type.get()) > 4;
}

bool File::isInteger(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  return H5Tget_class(type.get()) == H5T_INTEGER;
}

namespace {
template <typename T>
std::vector<T> readNumeric(const File& f, hid_t file, hid_t d, hid_t memType, const std::string& name) {
  Id type(H5Dget_type(d), H5Tclose);
  Id space(H5Dget_space(d), H5Sclose);
  requireSound(f, type.get(), space.get(), name);
  if (!isNumeric(type.get())) f.bad(name, "not a numeric dataset");
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
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  return readNumeric<double>(*this, file_.get(), d.get(), H5T_NATIVE_DOUBLE, dataset);
}

std::vector<int64_t> File::readInts(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  return readNumeric<int64_t>(*this, file_.get(), d.get(), H5T_NATIVE_INT64, dataset);
}

std::vector<double> File::readRows(const std::string& dataset, uint64_t first, uint64_t count) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  Id space(H5Dget_space(d.get()), H5Sclose);
  requireSound(*this, type.get(), space.get(), dataset);
  if (!isNumeric(type.get())) bad(dataset, "not a numeric dataset");
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
  for (hsize_t c : cnt)
    n *= c; // within the whole dataspace's element count, checked above
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
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  Id space(H5Dget_space(d.get()), H5Sclose);
  requireSound(*this, type.get(), space.get(), dataset);
  if (H5Tget_class(type.get()) != H5T_STRING) bad(dataset, "not a string dataset");
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
    for (char* p : strings.ptrs)
      out.push_back(trimmed(p ? std::string(p, strnlen(p, kMaxStringBytes)) : ""));
    return out;
  }
  const size_t size = H5Tget_size(type.get());
  if (size > kMaxStringBytes) bad(dataset, strCat("strings of ", size, " bytes (at most 65536 are read)"));
  Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
  H5Tset_size(mt.get(), size + 1);
  H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
  std::vector<char> buf(size_t(n) * (size + 1), '\0');
  if (n && H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data()) < 0) bad(dataset, "cannot read");
  for (uint64_t i = 0; i < n; ++i)
    out.push_back(trimmed(std::string(buf.data() + i * (size + 1), size)));
  return out;
}

CompoundTable File::readCompound(const std::string& dataset) const {
  const Lock lock(libraryLock());
  const Id d = openDataset(dataset);
  Id type(H5Dget_type(d.get()), H5Tclose);
  Id space(H5Dget_space(d.get()), H5Sclose);
  requireSound(*this, type.get(), space.get(), dataset);
  if (H5Tget_class(type.get()) != H5T_COMPOUND) bad(dataset, "not a compound dataset");
  CompoundLayout layout;
  std::string problem;
  if (!compoundLayout(type.get(), layout, problem)) bad(dataset, problem);
  const uint64_t n = elementCount(space.get());
  if (n > kMaxElements || n * layout.size > (uint64_t(1) << 34)) bad(dataset, "dataset too large");
  checkStorage(*this, file_.get(), d.get(), n, dataset);
  std::vector<unsigned char> buf =
      io::allocate<unsigned char>(n * layout.size, [&] { return strCat(path_, ": ", dataset); });
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
  const Lock lock(libraryLock());
  if (!exists(object)) return false;
  const std::vector<std::string>& names = attributes(object);
  return std::binary_search(names.begin(), names.end(), name);
}

Id File::openAttribute(const std::string& object, const std::string& name, Id& holder) const {
  const std::vector<std::string>& names = attributes(object);
  if (!std::binary_search(names.begin(), names.end(), name)) bad(object, "missing attribute '" + name + "'");
  holder = openObject(object);
  Id a(H5Aopen(holder.get(), name.c_str(), H5P_DEFAULT), H5Aclose);
  if (!a) bad(object, "cannot open attribute '" + name + "'");
  return a;
}

std::vector<double> File::attrNumbers(const std::string& object, const std::string& name) const {
  const Lock lock(libraryLock());
  Id holder;
  const Id a = openAttribute(object, name, holder);
  std::vector<double> out;
  std::string problem;
  if (!readAttributeNumbers(a.get(), name, out, problem)) bad(object, problem);
  return out;
}

std::string File::attrString(const std::string& object, const std::string& name) const {
  const Lock lock(libraryLock());
  Id holder;
  const Id a = openAttribute(object, name, holder);
  std::string out, problem;
  if (!readAttributeString(a.get(), name, out, problem)) bad(object, problem);
  return out;
}

} // namespace exa::h5

namespace exa {} // namespace exa
