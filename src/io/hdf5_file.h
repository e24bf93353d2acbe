// A thin read-only layer over the HDF5 C library for the simulation-code readers: owned ids,
// whole-dataset and row-range reads converted to double or int64, attributes, and every failure
// turned into exa::Error naming the file and the object. HDF5's own error printing is silenced.
#pragma once

#include "exabricks/core/error.h"

#include <hdf5.h>

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace exa::h5 {

/// True when the file carries the HDF5 signature (at offset 0 or a power of two from 512 on).
bool hasSignature(const std::string& path);

/// An owned HDF5 id, closed with the matching H5?close function.
class Id {
public:
  using Closer = herr_t (*)(hid_t);
  Id() = default;
  Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), closer_(o.closer_) {}
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      closer_ = o.closer_;
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  ~Id() { reset(); }
  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }
  void reset() {
    if (id_ >= 0 && closer_) closer_(id_);
    id_ = H5I_INVALID_HID;
  }

private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

/// One named member of a compound record, as read by readCompound.
struct CompoundTable {
  std::vector<std::string> members; ///< member names in file order
  std::vector<double> values;       ///< members.size() values per record (numeric members)
  std::vector<std::string> strings; ///< one string per record and string member
  size_t records = 0;
};

/// The error checkInChild throws: the file crashed libhdf5 (or made it hang, run out of memory
/// or report a damaged structure) in the child. Probes pass it on instead of taking the file
/// for another format.
class DamagedFile : public Error {
public:
  using Error::Error;
};

/// Checks that libhdf5 can walk the file's metadata without crashing, in a child process: it
/// opens the file and reads every group listing, object header, attribute and dataset
/// description the readers can ask for (and the first element of each dataset), as File does.
/// A child that dies by a signal, runs out of memory, takes longer than a minute (plus a second
/// per GB of file) or meets a group, attribute list, object header or chunk index that libhdf5
/// cannot read makes this fail (DamagedFile) naming the file and the object. A file that
/// passed is not checked again while it stays the same (device, inode, size and times, and for
/// a file changed in the last seconds a hash of its bytes). File calls it.
void checkInChild(const std::string& path);

/// Turns checkInChild on (the default) or off for this process. Only the structure-aware fuzz
/// targets turn it off: they write well-formed HDF5 with libhdf5 itself for every input, and
/// a process per input would slow them tenfold.
void setChildCheck(bool enabled);

/// A read-only HDF5 file. Object paths are absolute ("/level_0/boxes") or relative to the root.
/// Opening one first runs checkInChild. Every call holds one process-wide lock, so that the
/// check never forks while another thread is inside libhdf5. Names are looked up in the
/// listings of their groups and objects (never by asking libhdf5 about a name that may not
/// exist), and every datatype and dataspace is checked before anything is read or converted.
class File {
public:
  explicit File(const std::string& path);
  ~File();
  File(const File&) = delete;
  File& operator=(const File&) = delete;
  const std::string& path() const { return path_; }

  /// True when every link on the path exists.
  bool exists(const std::string& object) const;
  /// Names of a group's members, in name order.
  std::vector<std::string> members(const std::string& group) const;
  bool isDataset(const std::string& object) const;

  /// Dimensions of a dataset (outermost first).
  std::vector<uint64_t> dims(const std::string& dataset) const;
  /// Fails unless the dataset's storage lies within the file and can hold every element it
  /// declares (the reads check this too; readers call it before reserving memory by the shape).
  void requireStorage(const std::string& dataset) const;
  /// True when the dataset stores floating-point values of more than 4 bytes.
  bool isDouble(const std::string& dataset) const;
  /// True when the dataset stores integers.
  bool isInteger(const std::string& dataset) const;
  /// The whole dataset, converted.
  std::vector<double> readDoubles(const std::string& dataset) const;
  std::vector<int64_t> readInts(const std::string& dataset) const;
  /// Rows [first, first + count) along the outermost dimension, converted.
  std::vector<double> readRows(const std::string& dataset, uint64_t first, uint64_t count) const;
  /// Fixed- or variable-length strings of a string dataset, trailing blanks and NULs removed.
  std::vector<std::string> readStrings(const std::string& dataset) const;
  /// A compound dataset whose members are numbers or strings.
  CompoundTable readCompound(const std::string& dataset) const;

  bool hasAttribute(const std::string& object, const std::string& name) const;
  /// Numeric attribute values (a compound of numbers gives its members in order).
  std::vector<double> attrNumbers(const std::string& object, const std::string& name) const;
  std::string attrString(const std::string& object, const std::string& name) const;

  /// Throws exa::Error "FILE: OBJECT: what".
  [[noreturn]] void bad(const std::string& object, const std::string& what) const;

private:
  Id openObject(const std::string& object) const;
  Id openDataset(const std::string& dataset) const;
  Id openAttribute(const std::string& object, const std::string& name, Id& holder) const;
  /// Link names of a group (sorted; empty when it is not a group), listed once.
  const std::vector<std::string>& links(const std::string& group) const;
  /// Attribute names of an existing object (sorted), listed once.
  const std::vector<std::string>& attributes(const std::string& object) const;
  std::string path_;
  Id file_;
  mutable std::map<std::string, std::vector<std::string>> links_, attributes_;
};

} // namespace exa::h5
