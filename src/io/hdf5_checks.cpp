#include "hdf5_checks.h"

#include "exabricks/core/error.h"

#include "checked.h"

#include <algorithm>
#include <cstring>

namespace exa::h5::detail {
namespace {

// Members of a compound datatype, and how deep compounds may nest.
constexpr int kMaxMembers = 4096;
constexpr int kMaxTypeDepth = 4;
// Attributes of one object and links of one group that are looked at.
constexpr size_t kMaxAttributes = 4096;
constexpr size_t kMaxLinks = size_t(1) << 24;

/// Collects link or attribute names (at most kMaxLinks); stops the iteration past that.
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
  if (info && info->type != H5L_TYPE_HARD) {
    std::string marked(1, '\1');
    marked += name ? name : "";
    return collectName(marked.c_str(), out);
  }
  return collectName(name, out);
}
herr_t collectAttribute(hid_t, const char* name, const H5A_info_t*, void* out) { return collectName(name, out); }

} // namespace

std::recursive_mutex& libraryLock() {
  static std::recursive_mutex m;
  return m;
}

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

bool typeIsSound(hid_t type, std::string& problem, int depth) {
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

Listing listLinks(hid_t file, const std::string& group, std::vector<std::string>& names, std::vector<uint8_t>* soft) {
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

} // namespace exa::h5::detail
