#include "hdf5_file.h"

#include "exabricks/core/error.h"
#include "exabricks/core/log.h"

#include "checked.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <memory>
#include <mutex>
#include <set>
#include <tuple>

#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define EXABRICKS_H5_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define EXABRICKS_H5_ASAN 1
#endif
#endif

// Sanitizer runtimes (sanitizer builds and fuzz targets) report errors through a death callback
// that a fuzzer sets; the checking child clears it, so that a crash there is only the child's.
extern "C" void __sanitizer_set_death_callback(void (*callback)(void)) __attribute__((weak));

namespace exa::h5 {
namespace {

// Nothing the readers ask for is larger; a corrupt header must not make us allocate terabytes.
constexpr uint64_t kMaxElements = uint64_t(1) << 33;
// Longest fixed-length string (dataset element, attribute or compound member) that is read.
constexpr size_t kMaxStringBytes = size_t(1) << 16;
// Members of a compound datatype, and how deep compounds may nest.
constexpr int kMaxMembers = 4096;
constexpr int kMaxTypeDepth = 4;
// Attributes of one object, links of one group, and objects of one file that are looked at.
constexpr size_t kMaxAttributes = 4096;
constexpr size_t kMaxLinks = size_t(1) << 24;
constexpr size_t kMaxObjects = size_t(1) << 20;
// How long the checking child may take (plus a second per GB of file, for the chunk indexes of
// large files), and the memory it may map beyond what it inherits.
constexpr int kCheckSeconds = 60;
#ifndef EXABRICKS_H5_ASAN
constexpr uint64_t kCheckMemory = uint64_t(2) << 30;
#endif

/// Every call into libhdf5 holds this lock: the check forks only while no other thread is
/// inside the library (whose own locks a child would inherit held).
std::recursive_mutex& libraryLock() {
  static std::recursive_mutex m;
  return m;
}
using Lock = std::lock_guard<std::recursive_mutex>;

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
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0'))
    s.pop_back();
  return s;
}

bool isNumeric(hid_t type) {
  const H5T_class_t c = H5Tget_class(type);
  return c == H5T_INTEGER || c == H5T_FLOAT;
}

/// False, with the problem, for a datatype whose description would make libhdf5's conversions
/// read or write outside their buffers: numbers whose bit fields leave the element, compound
/// members outside the record, nesting beyond kMaxTypeDepth.
bool typeIsSound(hid_t type, std::string& problem, int depth = 0) {
  const H5T_class_t c = H5Tget_class(type);
  const size_t size = H5Tget_size(type);
  if (c == H5T_NO_CLASS || c < 0 || size == 0) {
    problem = "unreadable datatype";
    return false;
  }
  if (c == H5T_INTEGER || c == H5T_FLOAT) {
    const size_t bits = 8 * size, precision = H5Tget_precision(type);
    const int offset = H5Tget_offset(type);
    const H5T_order_t order = H5Tget_order(type);
    if (size > 16 || precision == 0 || offset < 0 || precision > bits || size_t(offset) > bits - precision ||
        (order != H5T_ORDER_LE && order != H5T_ORDER_BE)) {
      problem = strCat("corrupt number type (", size, " bytes, precision ", precision, " at bit ", offset, ")");
      return false;
    }
    if (c == H5T_FLOAT) {
      size_t spos = 0, epos = 0, esize = 0, mpos = 0, msize = 0;
      if (H5Tget_fields(type, &spos, &epos, &esize, &mpos, &msize) < 0 || spos >= bits || esize == 0 || esize > 32 ||
          epos > bits - esize || msize == 0 || msize > bits || mpos > bits - msize ||
          H5Tget_norm(type) == H5T_NORM_ERROR) {
        problem = strCat("corrupt floating-point type (", size, " bytes, exponent ", esize, " bits at ", epos,
                         ", mantissa ", msize, " bits at ", mpos, ")");
        return false;
      }
    }
    return true;
  }
  if (c == H5T_COMPOUND) {
    const int n = H5Tget_nmembers(type);
    if (n <= 0 || n > kMaxMembers || depth >= kMaxTypeDepth) {
      problem = strCat("corrupt compound type (", n, " members)");
      return false;
    }
    for (int i = 0; i < n; ++i) {
      const Id member(H5Tget_member_type(type, unsigned(i)), H5Tclose);
      const size_t at = H5Tget_member_offset(type, unsigned(i));
      const size_t bytes = member ? H5Tget_size(member.get()) : 0;
      if (!member || bytes == 0 || at > size || bytes > size - at) {
        problem = strCat("corrupt compound type (member ", i, " of ", bytes, " bytes at offset ", at,
                         " in a record of ", size, " bytes)");
        return false;
      }
      if (!typeIsSound(member.get(), problem, depth + 1)) return false;
    }
  }
  return true;
}

/// False, with the problem, for a dataspace that is neither scalar, null nor simple, or whose
/// dimensions multiply past 2^62 elements.
bool spaceIsSound(hid_t space, std::string& problem) {
  const H5S_class_t c = H5Sget_simple_extent_type(space);
  if (c == H5S_SCALAR || c == H5S_NULL) return true;
  const int rank = H5Sget_simple_extent_ndims(space);
  if (c != H5S_SIMPLE || rank < 0 || rank > H5S_MAX_RANK) {
    problem = "corrupt dataspace";
    return false;
  }
  std::vector<hsize_t> dims(size_t(rank), 0);
  if (rank > 0 && H5Sget_simple_extent_dims(space, dims.data(), nullptr) < 0) {
    problem = "corrupt dataspace";
    return false;
  }
  uint64_t n = 1;
  for (hsize_t d : dims)
    if (!io::productWithin(n, uint64_t(d), uint64_t(1) << 62, n)) {
      problem = "dataspace of more than 2^62 elements";
      return false;
    }
  return true;
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
  if (!typeIsSound(fileType, problem)) return false;
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

/// Link names of a group in name order (at most kMaxLinks); false when it cannot be listed.
/// The file's own reads and the check in the child list groups with this same call.
herr_t collectName(const char* name, void* out) {
  auto* names = static_cast<std::vector<std::string>*>(out);
  if (names->size() >= kMaxLinks) return 1;
  try {
    names->emplace_back(name ? name : "");
  } catch (...) {
    return -1;
  }
  return 0;
}
/// Links as names, soft links marked by a leading '\1' (a character no HDF5 name starts with).
herr_t collectLink(hid_t, const char* name, const H5L_info_t* info, void* out) {
  // External links lead to other files: they are not followed (the readers never use them).
  if (info && info->type == H5L_TYPE_EXTERNAL) return 0;
  if (info && info->type != H5L_TYPE_HARD) return collectName(("\1" + std::string(name ? name : "")).c_str(), out);
  return collectName(name, out);
}
herr_t collectAttribute(hid_t, const char* name, const H5A_info_t*, void* out) { return collectName(name, out); }

enum class Listing { Listed, NotAGroup, Failed };

/// A group's links in name order; `soft` (when given) marks the soft ones.
Listing listLinks(hid_t file, const std::string& group, std::vector<std::string>& names,
                  std::vector<uint8_t>* soft = nullptr) {
  names.clear();
  const Id g(H5Gopen2(file, group.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g) return Listing::NotAGroup;
  hsize_t at = 0;
  if (H5Literate(g.get(), H5_INDEX_NAME, H5_ITER_INC, &at, collectLink, &names) < 0) {
    names.clear();
    return Listing::Failed;
  }
  for (std::string& n : names)
    if (!n.empty() && n[0] == '\1') n.erase(0, 1) += '\1';
  std::sort(names.begin(), names.end());
  if (soft) soft->assign(names.size(), 0);
  for (size_t i = 0; i < names.size(); ++i)
    if (!names[i].empty() && names[i].back() == '\1') {
      names[i].pop_back();
      if (soft) (*soft)[i] = 1;
    }
  return Listing::Listed;
}

/// Attribute names of an open object in name order (at most kMaxAttributes).
bool listAttributes(hid_t object, std::vector<std::string>& names) {
  names.clear();
  hsize_t at = 0;
  if (H5Aiterate2(object, H5_INDEX_NAME, H5_ITER_INC, &at, collectAttribute, &names) < 0) {
    names.clear();
    return false;
  }
  if (names.size() > kMaxAttributes) names.resize(kMaxAttributes);
  std::sort(names.begin(), names.end());
  return true;
}

/// An attribute's numbers (a compound of numbers gives its members in order); false with the
/// problem otherwise. Shared by File::attrNumbers and the check in the child.
bool readAttributeNumbers(hid_t a, const std::string& name, std::vector<double>& out, std::string& problem) {
  const Id type(H5Aget_type(a), H5Tclose);
  const Id space(H5Aget_space(a), H5Sclose);
  if (!type || !space || !typeIsSound(type.get(), problem) || !spaceIsSound(space.get(), problem)) {
    problem = "attribute '" + name + "': " + (problem.empty() ? "unreadable" : problem);
    return false;
  }
  const uint64_t n = elementCount(space.get());
  if (n > 4096) {
    problem = "attribute '" + name + "' is too large";
    return false;
  }
  if (isNumeric(type.get())) {
    out.assign(static_cast<size_t>(n), 0.0);
    if (n && H5Aread(a, H5T_NATIVE_DOUBLE, out.data()) < 0) {
      problem = "cannot read attribute '" + name + "'";
      return false;
    }
    return true;
  }
  if (H5Tget_class(type.get()) == H5T_COMPOUND) {
    CompoundLayout layout;
    if (!compoundLayout(type.get(), layout, problem)) {
      problem = "attribute '" + name + "': " + problem;
      return false;
    }
    std::vector<unsigned char> buf(size_t(n) * layout.size);
    if (n && H5Aread(a, layout.type.get(), buf.data()) < 0) {
      problem = "cannot read attribute '" + name + "'";
      return false;
    }
    out.clear();
    for (uint64_t r = 0; r < n; ++r)
      for (size_t m = 0; m < layout.names.size(); ++m) {
        if (layout.stringSizes[m] != 0) {
          problem = "attribute '" + name + "' holds strings, expected numbers";
          return false;
        }
        double v;
        std::memcpy(&v, buf.data() + r * layout.size + layout.offsets[m], sizeof v);
        out.push_back(v);
      }
    return true;
  }
  problem = "attribute '" + name + "' is not numeric";
  return false;
}

/// An attribute holding one string; false with the problem otherwise. Shared by
/// File::attrString and the check in the child.
bool readAttributeString(hid_t a, const std::string& name, std::string& out, std::string& problem) {
  const Id type(H5Aget_type(a), H5Tclose);
  const Id space(H5Aget_space(a), H5Sclose);
  if (!type || !space || !typeIsSound(type.get(), problem) || !spaceIsSound(space.get(), problem)) {
    problem = "attribute '" + name + "': " + (problem.empty() ? "unreadable" : problem);
    return false;
  }
  if (H5Tget_class(type.get()) != H5T_STRING) {
    problem = "attribute '" + name + "' is not a string";
    return false;
  }
  if (elementCount(space.get()) != 1) {
    problem = "attribute '" + name + "' is not a single string";
    return false;
  }
  Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
  if (H5Tis_variable_str(type.get())) {
    H5Tset_size(mt.get(), H5T_VARIABLE);
    VlenStrings strings{mt.get(), space.get(), std::vector<char*>(1, nullptr)};
    if (H5Aread(a, mt.get(), strings.ptrs.data()) < 0) {
      problem = "cannot read attribute '" + name + "'";
      return false;
    }
    const char* p = strings.ptrs[0];
    out = trimmed(p ? std::string(p, strnlen(p, kMaxStringBytes)) : "");
    return true;
  }
  const size_t size = H5Tget_size(type.get());
  if (size > kMaxStringBytes) {
    problem = strCat("attribute '", name, "' is a string of ", size, " bytes (at most 65536 are read)");
    return false;
  }
  H5Tset_size(mt.get(), size + 1);
  H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
  std::string buf(size + 1, '\0');
  if (H5Aread(a, mt.get(), buf.data()) < 0) {
    problem = "cannot read attribute '" + name + "'";
    return false;
  }
  out = trimmed(std::string(buf.c_str()));
  return true;
}

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

// --- The check in a child process ---------------------------------------------------------

/// What the child writes for the parent: the object it is reading, and the first structural
/// failure libhdf5 reported (empty when none).
struct Shared {
  char at[2048];
  char fault[2048];
  bool unopened; ///< H5Fopen failed
};

/// Reads, in the child, everything of the file that File can ask libhdf5 for: every group's
/// listing (and each listed name looked up), every object's header and attributes (read as
/// numbers or strings, as File reads them), every dataset's type, dataspace, layout, storage
/// and chunk index, and its first element (all of a small table or string dataset). No
/// exception leaves it. A structural failure (a group or attribute list, an object header, a
/// chunk index that libhdf5 cannot read) is recorded: libhdf5's error paths on damaged
/// metadata are not safe either (freeing what was never allocated), so the parent must not
/// take them. Failures reading data are left to the reader to meet.
class Walk {
public:
  Walk(hid_t file, Shared* shared) : file_(file), shared_(shared) {}

  void object(const std::string& path, bool soft, int depth) {
    if (++objects_ > kMaxObjects || depth > 64) return;
    at(path);
    H5O_info_t info;
    if (H5Oget_info_by_name(file_, path.c_str(), &info, H5P_DEFAULT) < 0) {
      if (!soft) fault(path + " (object header)"); // a soft link may dangle
      return;
    }
    const bool seen = !visited_.insert(info.addr).second;
    if (seen) return; // a second link to an object already read
    {
      const Id o(H5Oopen(file_, path.c_str(), H5P_DEFAULT), H5Oclose);
      if (!o) return fault(path + " (object)");
      attributes(o.get(), path);
    }
    if (info.type == H5O_TYPE_DATASET) dataset(path);
    if (info.type != H5O_TYPE_GROUP) return;
    std::vector<std::string> names;
    std::vector<uint8_t> softLinks;
    if (listLinks(file_, path, names, &softLinks) != Listing::Listed) return fault(path + " (group members)");
    for (size_t i = 0; i < names.size(); ++i)
      object(path == "/" ? "/" + names[i] : path + "/" + names[i], softLinks[i] != 0, depth + 1);
  }

  void fault(const std::string& what) {
    if (shared_->fault[0]) return;
    const size_t n = std::min(what.size(), sizeof shared_->fault - 1);
    std::memcpy(shared_->fault, what.data(), n);
    shared_->fault[n] = '\0';
  }

private:
  void at(const std::string& what) {
    const size_t n = std::min(what.size(), sizeof shared_->at - 1);
    std::memcpy(shared_->at, what.data(), n);
    shared_->at[n] = '\0';
  }

  void attributes(hid_t o, const std::string& path) {
    std::vector<std::string> names;
    if (!listAttributes(o, names)) return fault(path + " (attributes)");
    for (const std::string& name : names) {
      at(path + " (attribute '" + name + "')");
      const Id a(H5Aopen(o, name.c_str(), H5P_DEFAULT), H5Aclose);
      if (!a) return fault(path + " (attribute '" + name + "')");
      const Id type(H5Aget_type(a.get()), H5Tclose);
      const Id space(H5Aget_space(a.get()), H5Sclose);
      if (!type || !space) return fault(path + " (attribute '" + name + "')");
      std::string problem, text;
      std::vector<double> numbers;
      if (H5Tget_class(type.get()) == H5T_STRING)
        readAttributeString(a.get(), name, text, problem);
      else
        readAttributeNumbers(a.get(), name, numbers, problem);
      if (problem.rfind("cannot read", 0) == 0) return fault(path + " (attribute '" + name + "')");
    }
  }

  void dataset(const std::string& path) {
    const Id d(H5Dopen2(file_, path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!d) return fault(path + " (dataset)");
    const Id type(H5Dget_type(d.get()), H5Tclose);
    const Id space(H5Dget_space(d.get()), H5Sclose);
    const Id plist(H5Dget_create_plist(d.get()), H5Pclose);
    if (!type || !space || !plist) return fault(path + " (dataset)");
    std::string problem;
    if (!typeIsSound(type.get(), problem) || !spaceIsSound(space.get(), problem)) return; // refused in the parent
    H5Pget_nfilters(plist.get());
    H5D_space_status_t allocated = H5D_SPACE_STATUS_ERROR;
    if (H5Dget_space_status(d.get(), &allocated) < 0) return fault(path + " (dataset)");
    // A dataset never written has no chunk index (the readers refuse it for its storage).
    if (H5Pget_layout(plist.get()) == H5D_CHUNKED && allocated != H5D_SPACE_STATUS_NOT_ALLOCATED) {
      at(path + " (chunk index)");
      hsize_t chunks = 0;
      if (H5Dget_num_chunks(d.get(), H5S_ALL, &chunks) < 0) return fault(path + " (chunk index)");
    }
    H5Dget_storage_size(d.get());
    const uint64_t n = elementCount(space.get());
    if (n == 0) return;
    at(path + " (first element)");
    const H5T_class_t c = H5Tget_class(type.get());
    if (c == H5T_INTEGER || c == H5T_FLOAT) {
      first(d.get(), space.get(), H5T_NATIVE_DOUBLE, sizeof(double));
      first(d.get(), space.get(), H5T_NATIVE_INT64, sizeof(int64_t));
    } else if (c == H5T_COMPOUND) {
      CompoundLayout layout;
      if (compoundLayout(type.get(), layout, problem)) {
        // Small tables whole (as File::readCompound reads them), else the first record.
        if (n * layout.size <= (uint64_t(1) << 20)) {
          std::vector<unsigned char> buf(size_t(n) * layout.size);
          H5Dread(d.get(), layout.type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
        } else {
          first(d.get(), space.get(), layout.type.get(), layout.size);
        }
      }
    } else if (c == H5T_STRING && n <= 4096) {
      at(path + " (strings)");
      Id mt(H5Tcopy(H5T_C_S1), H5Tclose);
      if (H5Tis_variable_str(type.get())) {
        H5Tset_size(mt.get(), H5T_VARIABLE);
        VlenStrings strings{mt.get(), space.get(), std::vector<char*>(static_cast<size_t>(n), nullptr)};
        H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, strings.ptrs.data());
      } else if (H5Tget_size(type.get()) <= kMaxStringBytes) {
        const size_t size = H5Tget_size(type.get());
        H5Tset_size(mt.get(), size + 1);
        H5Tset_strpad(mt.get(), H5T_STR_NULLTERM);
        std::vector<char> buf(size_t(n) * (size + 1), '\0');
        H5Dread(d.get(), mt.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
      }
    }
  }

  /// Reads the dataset's first element as `memType`.
  void first(hid_t d, hid_t space, hid_t memType, size_t bytes) {
    std::vector<unsigned char> buf(bytes);
    const int rank = H5Sget_simple_extent_ndims(space);
    if (rank <= 0) {
      H5Dread(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
      return;
    }
    const Id file(H5Scopy(space), H5Sclose);
    const std::vector<hsize_t> start(size_t(rank), 0), count(size_t(rank), 1);
    if (!file || H5Sselect_hyperslab(file.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr) < 0)
      return;
    const hsize_t one = 1;
    const Id mem(H5Screate_simple(1, &one, nullptr), H5Sclose);
    H5Dread(d, memType, mem.get(), file.get(), H5P_DEFAULT, buf.data());
  }

  hid_t file_;
  Shared* shared_;
  size_t objects_ = 0;
  std::set<haddr_t> visited_;
};

/// The file as the check last saw it: a file that passed is not checked again while this stays.
/// A file changed within the last seconds (whose times a change in the same tick of the file
/// system's clock would not move) is also identified by a hash of its bytes.
struct Identity {
  dev_t dev;
  ino_t ino;
  off_t size;
  long mtimeSec, mtimeNsec, ctimeSec, ctimeNsec;
  uint64_t content = 0;
  auto key() const { return std::tie(dev, ino, size, mtimeSec, mtimeNsec, ctimeSec, ctimeNsec, content); }
  bool operator<(const Identity& o) const { return key() < o.key(); }
};

// Files changed this recently are hashed (up to kHashBytes; larger ones are checked every time).
constexpr long kRecentSeconds = 2;
constexpr uint64_t kHashBytes = uint64_t(64) << 20;

/// FNV-1a of the file's bytes, or false when it cannot be read.
bool hashFile(const std::string& path, uint64_t& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  uint64_t h = 0xcbf29ce484222325ull;
  std::vector<char> buf(size_t(1) << 16);
  while (in) {
    in.read(buf.data(), std::streamsize(buf.size()));
    const std::streamsize n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i)
      h = (h ^ uint64_t(static_cast<unsigned char>(buf[size_t(i)]))) * 0x100000001b3ull;
  }
  out = h;
  return in.eof();
}

bool& childCheck() {
  static bool enabled = true;
  return enabled;
}

std::set<Identity>& checkedFiles() {
  static std::set<Identity> files;
  return files;
}

#ifndef EXABRICKS_H5_ASAN
long mappedBytes() {
  std::ifstream in("/proc/self/statm");
  long pages = 0;
  in >> pages;
  return pages * sysconf(_SC_PAGESIZE);
}
#endif

/// The child: plain deaths on fatal signals (no handlers inherited from the parent, no core
/// files), a memory and CPU limit, then the walk; exits 0 whatever libhdf5 reports.
[[noreturn]] void runCheck(const std::string& path, Shared* shared, long seconds) {
  for (int sig : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT, SIGTRAP, SIGSYS})
    std::signal(sig, SIG_DFL);
  if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(nullptr);
  const rlimit noCore{0, 0};
  setrlimit(RLIMIT_CORE, &noCore);
  const rlimit cpu{rlim_t(seconds + 5), rlim_t(seconds + 5)};
  setrlimit(RLIMIT_CPU, &cpu);
#ifndef EXABRICKS_H5_ASAN
  const rlim_t memory = rlim_t(uint64_t(mappedBytes()) + kCheckMemory);
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && (as.rlim_cur == RLIM_INFINITY || as.rlim_cur > memory)) {
    as.rlim_cur = memory;
    setrlimit(RLIMIT_AS, &as);
  }
#endif
  try {
    silence();
    Id access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    if (access) H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
    const Id file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, access ? access.get() : H5P_DEFAULT), H5Fclose);
    Walk walk(file.get(), shared);
    if (file)
      walk.object("/", false, 0);
    else
      shared->unopened = true;
  } catch (...) {
  }
  _exit(0);
}

} // namespace

void setChildCheck(bool enabled) {
  const Lock lock(libraryLock());
  childCheck() = enabled;
}

void checkInChild(const std::string& path) {
  const Lock lock(libraryLock());
  if (!childCheck()) return;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return; // opening it reports that
  Identity identity{st.st_dev,
                    st.st_ino,
                    st.st_size,
                    long(st.st_mtim.tv_sec),
                    long(st.st_mtim.tv_nsec),
                    long(st.st_ctim.tv_sec),
                    long(st.st_ctim.tv_nsec)};
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const bool recent = long(now.tv_sec) - std::max(identity.mtimeSec, identity.ctimeSec) < kRecentSeconds;
  const bool remember = !recent || (uint64_t(st.st_size) <= kHashBytes && hashFile(path, identity.content));
  if (remember && checkedFiles().count(identity)) return;

  void* page = ::mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  int done[2] = {-1, -1}; // closed by the child's end: wakes the parent at once
  if (page == MAP_FAILED || ::pipe2(done, O_CLOEXEC) != 0) {
    if (page != MAP_FAILED) ::munmap(page, sizeof(Shared));
    logWarning(strCat(path, ": cannot check the HDF5 file in a separate process (", std::strerror(errno),
                      "); reading it directly"));
    return;
  }
  const std::unique_ptr<void, void (*)(void*)> unmap(page, [](void* p) { ::munmap(p, sizeof(Shared)); });
  Shared* shared = static_cast<Shared*>(page); // zeros, as mapped
  std::strcpy(shared->at, "the superblock and the root group");
  const long seconds = kCheckSeconds + long(st.st_size >> 30);
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(done[0]);
    runCheck(path, shared, seconds);
  }
  ::close(done[1]);
  if (pid < 0) {
    ::close(done[0]);
    logWarning(strCat(path, ": cannot check the HDF5 file in a separate process (", std::strerror(errno),
                      "); reading it directly"));
    return;
  }
  int status = 0;
  bool timedOut = false;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) { // children reaped elsewhere (SIGCHLD ignored): no verdict
      ::close(done[0]);
      return;
    }
    const auto waited = std::chrono::steady_clock::now() - start;
    if (waited > std::chrono::seconds(seconds)) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      timedOut = true;
      break;
    }
    // Until the child's end of the pipe closes (it is ending: then wait for it), looking again
    // every 100 ms.
    pollfd fd{done[0], POLLIN, 0};
    if (::poll(&fd, 1, 100) > 0 && (fd.revents & POLLHUP)) {
      pid_t ended;
      while ((ended = ::waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
      }
      if (ended == pid) break;
      ::close(done[0]);
      return; // reaped elsewhere: no verdict
    }
  }
  ::close(done[0]);
  const std::string where(shared->at, strnlen(shared->at, sizeof shared->at));
  const std::string fault(shared->fault, strnlen(shared->fault, sizeof shared->fault));
  if (timedOut)
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 did not finish reading its metadata within ", seconds,
                             " s (at ", where, ")"));
  if (WIFSIGNALED(status))
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 crashed (", strsignal(WTERMSIG(status)), ") reading ",
                             where, " (found in a separate process; the file cannot be read)"));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw DamagedFile(strCat(path, ": damaged HDF5 file: reading ", where,
                             " failed in a separate process (exit status ",
                             WIFEXITED(status) ? WEXITSTATUS(status) : -1, "; out of memory?)"));
  if (shared->unopened)
    throw DamagedFile(strCat(path, ": cannot open as HDF5 (truncated or damaged file, or one locked by a writer?)"));
  if (!fault.empty())
    throw DamagedFile(strCat(path, ": damaged HDF5 file: libhdf5 cannot read ", fault,
                             " (found in a separate process; the file cannot be read)"));
  if (remember) checkedFiles().insert(identity);
}

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
