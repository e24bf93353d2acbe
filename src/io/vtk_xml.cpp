#include "vtk_xml.h"

#include "checked.h"
#include "exabricks/core/byte_order.h"

#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

namespace exa::io::vtk {
namespace {

std::string decodeBase64(const std::string& path, const std::string& what, const std::string& text, size_t& consumed,
                         size_t wantBytes) {
  static int8_t table[256];
  static bool init = [] {
    std::fill(std::begin(table), std::end(table), int8_t(-1));
    const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i)
      table[(unsigned char)a[i]] = int8_t(i);
    return true;
  }();
  (void)init;
  // Decodes whole 4-character groups from `consumed` until `wantBytes` bytes are out (or the
  // text ends); whitespace is skipped.
  std::string out;
  uint32_t acc = 0;
  int n = 0, pad = 0;
  size_t i = consumed;
  for (; i < text.size() && out.size() < wantBytes; ++i) {
    const unsigned char c = (unsigned char)text[i];
    if (std::isspace(c)) continue;
    if (c == '=') {
      ++pad;
      acc <<= 6;
    } else {
      if (table[c] < 0 || pad) fail(path, ": ", what, ": invalid base64 data");
      acc = (acc << 6) | uint32_t(table[c]);
    }
    if (++n == 4) {
      out.push_back(char((acc >> 16) & 0xff));
      if (pad < 2) out.push_back(char((acc >> 8) & 0xff));
      if (pad < 1) out.push_back(char(acc & 0xff));
      n = 0;
      acc = 0;
      if (pad) {
        ++i;
        break;
      }
    }
  }
  if (n != 0) fail(path, ": ", what, ": truncated base64 data");
  consumed = i;
  return out;
}

} // namespace

std::string readFile(const std::string& path, const std::string& role) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open ", role, ": ", std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<Tag> scanTags(const std::string& path, const std::string& xml, size_t end) {
  std::vector<Tag> tags;
  size_t pos = 0;
  while ((pos = xml.find('<', pos)) != std::string::npos && pos < end) {
    if (xml.compare(pos, 4, "<!--") == 0) {
      const size_t close = xml.find("-->", pos);
      if (close == std::string::npos) fail(path, ": byte ", pos, ": unterminated XML comment");
      pos = close + 3;
      continue;
    }
    const size_t close = xml.find('>', pos);
    if (close == std::string::npos || close > end)
      fail(path, ": byte ", pos, ": unterminated XML tag (truncated file?)");
    if (xml[pos + 1] == '?' || xml[pos + 1] == '!') {
      pos = close + 1;
      continue;
    }
    Tag t;
    t.offset = pos;
    size_t i = pos + 1;
    while (i < close && !std::isspace((unsigned char)xml[i]) && xml[i] != '/' && xml[i] != '>')
      ++i;
    if (xml[pos + 1] == '/') {
      while (i < close && !std::isspace((unsigned char)xml[i]) && xml[i] != '>')
        ++i;
    }
    t.name = xml.substr(pos + 1, i - pos - 1);
    while (i < close) {
      while (i < close && (std::isspace((unsigned char)xml[i]) || xml[i] == '/'))
        ++i;
      if (i >= close) break;
      const size_t eq = xml.find('=', i);
      if (eq == std::string::npos || eq > close) fail(path, ": byte ", i, ": malformed attribute in <", t.name, ">");
      std::string key = xml.substr(i, eq - i);
      while (!key.empty() && std::isspace((unsigned char)key.back()))
        key.pop_back();
      size_t q = eq + 1;
      while (q < close && std::isspace((unsigned char)xml[q]))
        ++q;
      if (q >= close || (xml[q] != '"' && xml[q] != '\''))
        fail(path, ": byte ", q, ": attribute '", key, "' of <", t.name, "> is not quoted");
      const size_t qe = xml.find(xml[q], q + 1);
      if (qe == std::string::npos || qe > close) fail(path, ": byte ", q, ": unterminated attribute '", key, "'");
      t.attrs[key] = xml.substr(q + 1, qe - q - 1);
      i = qe + 1;
    }
    const size_t next = std::min(xml.find('<', close + 1), end);
    t.text = xml.substr(close + 1, (next == std::string::npos ? end : next) - close - 1);
    tags.push_back(std::move(t));
    pos = close + 1;
  }
  return tags;
}

std::vector<double> numbers(const std::string& path, const std::string& text, size_t expected,
                            const std::string& what) {
  std::istringstream in(text);
  std::vector<double> v;
  for (double d; in >> d;)
    v.push_back(d);
  if (v.size() != expected || !in.eof()) fail(path, ": ", what, ": expected ", expected, " numbers, got '", text, "'");
  for (double d : v)
    if (!std::isfinite(d)) fail(path, ": ", what, ": not finite");
  return v;
}

Encoding encodingOf(const std::string& path, const Tag& vtkFile) {
  Encoding e;
  const std::string order = vtkFile.attr("byte_order", "LittleEndian");
  if (order == "BigEndian")
    e.bigEndian = true;
  else if (order != "LittleEndian")
    fail(path, ": unknown byte_order '", order, "'");
  const std::string header = vtkFile.attr("header_type", "UInt32");
  if (header == "UInt64")
    e.headerBytes = 8;
  else if (header != "UInt32")
    fail(path, ": unsupported header_type '", header, "' (UInt32 and UInt64 are read)");
  const std::string compressor = vtkFile.attr("compressor");
  if (compressor == "vtkZLibDataCompressor")
    e.zlib = true;
  else if (!compressor.empty())
    fail(path, ": compressor '", compressor,
         "' is not supported (vtkZLibDataCompressor is; re-save without compression)");
  return e;
}

std::string Base64Source::take(size_t n) {
  // VTK encodes the header and the (compressed) data as separate base64 streams, but the
  // uncompressed form as one; keep decoded leftovers so both work.
  while (buffer_.size() < n) {
    const std::string more = decodeBase64(path_, what_, text_, consumed_, n - buffer_.size());
    if (more.empty()) fail(path_, ": ", what_, ": truncated binary data");
    buffer_ += more;
  }
  std::string s = buffer_.substr(0, n);
  buffer_.erase(0, n);
  return s;
}

std::string readBlock(const std::string& path, const std::string& what, BlockSource& src, const Encoding& e,
                      uint64_t expectedBytes) {
  auto header = [&] {
    const std::string h = src.take(e.headerBytes);
    return io::loadUnsigned(reinterpret_cast<const unsigned char*>(h.data()), e.headerBytes, e.bigEndian);
  };
  if (!e.zlib) {
    const uint64_t n = header();
    if (n != expectedBytes) fail(path, ": ", what, ": block holds ", n, " bytes, expected ", expectedBytes);
    io::requireBytes(n, 1, src.left(), strCat(path, ": ", what));
    return src.take(size_t(n));
  }
  // The compression header: block count, nominal block size, size of the last block (0 when it
  // is a whole block), then the compressed size of each block. The nominal size may exceed a
  // small array (VTK writes 32768 for every array), so a single block may be shorter than it.
  const uint64_t blocks = header(), blockSize = header(), lastSize = header();
  const std::string where = strCat(path, ": ", what);
  if (blocks > 0 && blockSize == 0) fail(where, ": corrupt compression header (block size 0)");
  if (lastSize > blockSize)
    fail(where, ": corrupt compression header (last block of ", lastSize, " bytes, block size ", blockSize, ")");
  if (blocks > expectedBytes / std::max<uint64_t>(blockSize, 1) + 1)
    fail(where, ": corrupt compression header (", blocks, " blocks of ", blockSize, " bytes for ", expectedBytes,
         " bytes)");
  const uint64_t total = blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize == 0 ? blockSize : lastSize);
  if (total != expectedBytes) fail(where, ": compressed data holds ", total, " bytes, expected ", expectedBytes);
  io::requireBytes(blocks, e.headerBytes, src.left(), where + ": compressed block sizes");
  std::vector<uint64_t> sizes = io::allocate<uint64_t>(blocks, [&] { return where; });
  uint64_t packedTotal = 0;
  for (uint64_t& s : sizes) {
    s = header();
    if (s > src.left() - std::min(src.left(), packedTotal)) // packedTotal stays within the bytes left
      io::requireBytes(packedTotal + std::min(s, UINT64_MAX - packedTotal), 1, src.left(),
                       where + ": compressed blocks");
    packedTotal += s;
  }
  // Inflating never grows a block by more than kMaxInflate: bound the declared size by the
  // bytes present before reserving it.
  uint64_t inflatable = 0;
  if (io::productWithin(packedTotal + 1, io::kMaxInflate, UINT64_MAX, inflatable) && total > inflatable)
    fail(where, ": declares ", total, " bytes, more than its ", packedTotal, " compressed bytes can hold");
  std::string out;
  io::reserveMore(out, total, [&] { return where; });
  for (uint64_t b = 0; b < blocks; ++b) {
    const std::string packed = src.take(size_t(sizes[size_t(b)]));
    uLongf size = uLongf(b + 1 == blocks && lastSize != 0 ? lastSize : blockSize);
    std::string plain(size_t(size), '\0');
    const uLongf want = size;
    if (uncompress(reinterpret_cast<Bytef*>(plain.data()), &size, reinterpret_cast<const Bytef*>(packed.data()),
                   uLong(packed.size())) != Z_OK ||
        size != want)
      fail(path, ": ", what, ": zlib block ", b, " does not decompress (corrupt data)");
    out += plain;
  }
  return out;
}

size_t typeSize(const std::string& type) {
  static const std::map<std::string, size_t> sizes{{"Int8", 1},    {"UInt8", 1},  {"Int16", 2}, {"UInt16", 2},
                                                   {"Int32", 4},   {"UInt32", 4}, {"Int64", 8}, {"UInt64", 8},
                                                   {"Float32", 4}, {"Float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

double toDouble(const unsigned char* p, const std::string& type, bool bigEndian) {
  const size_t n = typeSize(type);
  const bool swap = io::needsSwap(bigEndian);
  if (type == "Float32") return io::loadScalar<float>(p, swap);
  if (type == "Float64") return io::loadScalar<double>(p, swap);
  const uint64_t u = io::loadUnsigned(p, n, bigEndian);
  if (type[0] == 'U') return double(u);
  const int64_t s = n == 8 ? int64_t(u) : int64_t(u << (64 - 8 * n)) >> (64 - 8 * n);
  return double(s);
}

} // namespace exa::io::vtk
