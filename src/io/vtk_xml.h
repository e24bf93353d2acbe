// The XML layer of the VTK readers (vtk_amr.cpp): files read whole, start tags and their
// attributes, the encoding of a VTKFile, and data arrays as VTK writes them (raw or base64,
// with a byte-count header or zlib block table), converted to double. Private to the io layer.
#pragma once

#include "exabricks/core/error.h"

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace exa::io::vtk {

/// The whole file; fails naming it (as a `role`) when it cannot be opened.
std::string readFile(const std::string& path, const std::string& role);

/// One XML start tag (or self-closing tag) with its attributes and the text that follows it up
/// to the next tag. VTK's XML is simple enough that this is all the readers need.
struct Tag {
  std::string name; ///< "/Name" for an end tag
  std::map<std::string, std::string> attrs;
  std::string text;
  size_t offset = 0; ///< byte offset of '<' in the file
  std::string attr(const std::string& key, const std::string& fallback = "") const {
    const auto it = attrs.find(key);
    return it == attrs.end() ? fallback : it->second;
  }
};

/// Tags of `xml` up to `end` (the start of raw appended data, which is not XML).
std::vector<Tag> scanTags(const std::string& path, const std::string& xml, size_t end);

/// `expected` finite numbers separated by blanks; fails naming `what` otherwise.
std::vector<double> numbers(const std::string& path, const std::string& text, size_t expected, const std::string& what);

/// Byte order, header width and compression of one VTKFile.
struct Encoding {
  bool bigEndian = false;
  size_t headerBytes = 4;
  bool zlib = false;
};

Encoding encodingOf(const std::string& path, const Tag& vtkFile);

/// A data block as VTK writes it: a header (byte count, or block table when compressed) and the
/// bytes. `src` is the raw bytes of an appended block or the decoded base64 stream.
class BlockSource {
public:
  virtual ~BlockSource() = default;
  /// The next `n` bytes (throws when there are fewer).
  virtual std::string take(size_t n) = 0;
  /// An upper bound of the bytes left: declared sizes are checked against it before anything
  /// is allocated for them.
  virtual uint64_t left() const = 0;
};

class RawSource : public BlockSource {
public:
  RawSource(const std::string& path, const std::string& what, const std::string& data, size_t at)
      : path_(path), what_(what), data_(data), at_(at) {}
  std::string take(size_t n) override {
    if (at_ > data_.size() || n > data_.size() - at_) fail(path_, ": ", what_, ": truncated appended data");
    std::string s = data_.substr(at_, n);
    at_ += n;
    return s;
  }
  uint64_t left() const override { return at_ > data_.size() ? 0 : data_.size() - at_; }

private:
  const std::string &path_, &what_, &data_;
  size_t at_;
};

class Base64Source : public BlockSource {
public:
  Base64Source(const std::string& path, const std::string& what, const std::string& text)
      : path_(path), what_(what), text_(text) {}
  std::string take(size_t n) override;
  uint64_t left() const override {
    return buffer_.size() + (consumed_ >= text_.size() ? 0 : (text_.size() - consumed_) / 4 * 3 + 3);
  }

private:
  const std::string &path_, &what_, &text_;
  size_t consumed_ = 0;
  std::string buffer_;
};

/// The bytes of one data block of `expectedBytes` bytes, its header (and zlib blocks) checked
/// against what the source holds before anything is allocated for them.
std::string readBlock(const std::string& path, const std::string& what, BlockSource& src, const Encoding& e,
                      uint64_t expectedBytes);

/// Bytes per value of a VTK scalar type, 0 for an unknown one.
size_t typeSize(const std::string& type);

/// The value of type `type` at p.
double toDouble(const unsigned char* p, const std::string& type, bool bigEndian);

} // namespace exa::io::vtk
