// What the HDF5 file wrapper (hdf5_file.cpp) and the check in a child process (hdf5_child.cpp)
// share: the process-wide library lock, the soundness checks of datatypes and dataspaces, group
// and attribute listings, and attribute reads. Private to the io layer.
#pragma once

#include "hdf5_file.h"

#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace exa::h5::detail {

// Longest fixed-length string (dataset element, attribute or compound member) that is read.
constexpr size_t kMaxStringBytes = size_t(1) << 16;

/// Every call into libhdf5 holds this lock: the check forks only while no other thread is
/// inside the library (whose own locks a child would inherit held).
std::recursive_mutex& libraryLock();
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

/// Turns off libhdf5's own error printing.
void silence();
/// `s` without trailing blanks and NULs.
std::string trimmed(std::string s);
bool isNumeric(hid_t type);

/// False, with the problem, for a datatype whose description would make libhdf5's conversions
/// read or write outside their buffers: numbers whose bit fields leave the element, compound
/// members outside the record, nesting beyond a few levels.
bool typeIsSound(hid_t type, std::string& problem, int depth = 0);

/// False, with the problem, for a dataspace that is neither scalar, null nor simple, or whose
/// dimensions multiply past 2^62 elements.
bool spaceIsSound(hid_t space, std::string& problem);

/// A memory compound with the file compound's member names: numbers as double, fixed strings
/// as NUL-terminated char arrays. Returns the type, fills the layout.
struct CompoundLayout {
  Id type;
  std::vector<size_t> offsets;
  std::vector<size_t> stringSizes; ///< 0 for numeric members
  std::vector<std::string> names;
  size_t size = 0;
};

bool compoundLayout(hid_t fileType, CompoundLayout& out, std::string& problem);

uint64_t elementCount(hid_t space);

enum class Listing { Listed, NotAGroup, Failed };

/// A group's links in name order; `soft` (when given) marks the soft ones. The file's own reads
/// and the check in the child list groups with this same call.
Listing listLinks(hid_t file, const std::string& group, std::vector<std::string>& names,
                  std::vector<uint8_t>* soft = nullptr);

/// Attribute names of an open object in name order (at most 4096).
bool listAttributes(hid_t object, std::vector<std::string>& names);

/// An attribute's numbers (a compound of numbers gives its members in order); false with the
/// problem otherwise. Shared by File::attrNumbers and the check in the child.
bool readAttributeNumbers(hid_t a, const std::string& name, std::vector<double>& out, std::string& problem);

/// An attribute holding one string; false with the problem otherwise. Shared by
/// File::attrString and the check in the child.
bool readAttributeString(hid_t a, const std::string& name, std::string& out, std::string& problem);

} // namespace exa::h5::detail
