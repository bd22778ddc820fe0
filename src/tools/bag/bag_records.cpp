#include "bag_records.hpp"  // NOLINT(build/include_subdir)

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <new>
#include <vector>

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include "drivetrain_stiffness/core/validation.hpp"

namespace drivetrain_stiffness::bag {
namespace {
std::string str(std::uint64_t n) { return std::to_string(n); }
}  // namespace

std::string opName(std::uint8_t op) {
  char s[8];
  std::snprintf(s, sizeof s, "0x%02x", op);
  return s;
}

std::string parseFields(const std::uint8_t* p, std::size_t n, Fields& fields) {
  return forEachField(p, n, [&](std::string_view name, std::string_view value) {
    fields[std::string(name)] = value;
  });
}

std::string parseChunkRecord(const std::uint8_t* p, std::size_t n, ChunkRecord& r, bool& cut_off) {
  cut_off = true;
  if (n < 4) return "record cut off inside its header length (" + str(n) + " of 4 bytes)";
  const std::uint32_t header_length = u32(p);
  if (n - 4 < header_length + std::size_t{4}) {
    return "record header of " + str(header_length) + " bytes runs past the chunk's end (" +
           str(n - 4) + " bytes left)";
  }
  r.data_length = u32(p + 4 + header_length);
  const std::size_t data_begin = 8 + std::size_t{header_length};
  if (r.data_length > n - data_begin) {
    return "record data of " + str(r.data_length) + " bytes runs past the chunk's end (" +
           str(n - data_begin) + " bytes left)";
  }
  cut_off = false;
  r.fields.clear();
  const std::string error = parseFields(p + 4, header_length, r.fields);
  if (!error.empty()) return error;
  if (!fixedField(r.fields, "op", r.op)) return "record header without a one-byte 'op' field";
  r.data = p + data_begin;
  r.length = data_begin + r.data_length;
  return "";
}

namespace {

/// LZ4 into a buffer of the claimed size, which the ratio bound keeps in proportion to the chunk.
std::string decompressLz4(const std::uint8_t* in, std::size_t in_size, std::uint32_t size,
                          std::unique_ptr<std::uint8_t[]>& out) {
  if (size > 255 * std::uint64_t{in_size} + 64) {
    return "this lz4 chunk of " + str(in_size) + " bytes claims " + str(size) +
           " uncompressed bytes, more than lz4 can expand to (a damaged size)";
  }
  out = allocateBytes(size);
  if (!out) return "cannot allocate the " + str(size) + " bytes its size field asks for";
  unsigned int written = size;
  const int rc = roslz4_buffToBuffDecompress(const_cast<char*>(reinterpret_cast<const char*>(in)),
                                             static_cast<unsigned int>(in_size),
                                             reinterpret_cast<char*>(out.get()), &written);
  if (rc != ROSLZ4_OK)
    return "this lz4 chunk does not decompress (roslz4 code " + std::to_string(rc) + ")";
  if (written != size)
    return "this lz4 chunk decompresses to " + str(written) + " bytes, its header says " +
           str(size);
  return "";
}

/// bz2 in steps, the buffer doubling with the output up to the claimed size.
std::string decompressBz2(const std::uint8_t* in, std::size_t in_size, std::uint32_t size,
                          std::unique_ptr<std::uint8_t[]>& out) {
  bz_stream z{};
  if (BZ2_bzDecompressInit(&z, 0, 0) != BZ_OK) return "libbz2 cannot start";
  z.next_in = const_cast<char*>(reinterpret_cast<const char*>(in));
  z.avail_in = static_cast<unsigned int>(in_size);
  std::size_t capacity = 0, written = 0;
  int rc = BZ_OK;
  std::string error;
  while (rc == BZ_OK && error.empty()) {
    if (written == capacity) {
      if (capacity == size + std::size_t{1}) {  // one byte past the claim: more data than it says
        error =
            "this bz2 chunk decompresses to more than the " + str(size) + " bytes its header says";
        break;
      }
      const std::size_t grown = std::min<std::size_t>(std::max<std::size_t>(2 * capacity, 1u << 16),
                                                      size + std::size_t{1});
      std::unique_ptr<std::uint8_t[]> bigger = allocateBytes(grown);
      if (!bigger) {
        error = "cannot allocate " + str(grown) + " bytes";
        break;
      }
      if (written) std::memcpy(bigger.get(), out.get(), written);
      out = std::move(bigger);
      capacity = grown;
    }
    z.next_out = reinterpret_cast<char*>(out.get() + written);
    z.avail_out = static_cast<unsigned int>(capacity - written);
    const unsigned int in_before = z.avail_in;
    const std::size_t out_before = written;
    rc = BZ2_bzDecompress(&z);
    written = capacity - z.avail_out;
    // Input ended mid-stream, or no progress with room for both: damaged data, never a spin.
    const bool stalled = z.avail_in == in_before && written == out_before;
    if (rc == BZ_OK && ((z.avail_in == 0 && z.avail_out > 0) || stalled)) rc = BZ_UNEXPECTED_EOF;
  }
  BZ2_bzDecompressEnd(&z);
  if (!error.empty()) return error;
  if (rc != BZ_STREAM_END)
    return "this bz2 chunk does not decompress (libbz2 code " + std::to_string(rc) + ")";
  if (written != size)
    return "this bz2 chunk decompresses to " + str(written) + " bytes, its header says " +
           str(size);
  return "";
}

}  // namespace

std::string decompressChunk(const std::string& compression, const std::uint8_t* in,
                            std::size_t in_size, std::uint32_t size,
                            std::unique_ptr<std::uint8_t[]>& out) {
  if (in_size > 0xffffffffu)
    return "compressed chunk of " + str(in_size) + " bytes (more than 4 GiB)";
  if (compression == "lz4") return decompressLz4(in, in_size, size, out);
  if (compression == "bz2") return decompressBz2(in, in_size, size, out);
  return "chunk compression '" + compression + "' unknown";
}

std::unique_ptr<std::uint8_t[]> allocateBytes(std::size_t n) {
  return std::unique_ptr<std::uint8_t[]>(new (std::nothrow) std::uint8_t[n > 0 ? n : 1]);
}

BagFile::BagFile(const std::string& path) {
  file_.reset(std::fopen(path.c_str(), "rb"));
  if (!file_) throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  if (fseeko(file_.get(), 0, SEEK_END) != 0)
    throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  size_ = static_cast<std::uint64_t>(ftello(file_.get()));
}

bool BagFile::readAt(std::uint64_t offset, void* out, std::size_t n) {
  return fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) == 0 &&
         std::fread(out, 1, n, file_.get()) == n;
}

std::string BagFile::readRecord(std::uint64_t offset, TopRecord& r) {
  r.offset = offset;
  const std::uint64_t left = size_ - offset;
  std::uint8_t length[4];
  if (left < 4)
    return "truncated: the file ends at byte " + str(size_) + " inside a record's header length";
  if (!readAt(offset, length, 4)) return std::string("read error: ") + std::strerror(errno);
  const std::uint32_t header_length = u32(length);
  if (left - 4 < header_length + std::uint64_t{4}) {
    return "the file ends at byte " + str(size_) + " inside this record (its header claims " +
           str(header_length) + " bytes): truncated, or a damaged length";
  }
  std::vector<std::uint8_t> header(header_length + std::size_t{4});
  if (!readAt(offset + 4, header.data(), header.size()))
    return std::string("read error: ") + std::strerror(errno);
  r.fields.clear();
  const std::string error = parseFields(header.data(), header_length, r.fields);
  if (!error.empty()) return "damaged record: " + error;
  if (!fixedField(r.fields, "op", r.op))
    return "damaged record: header without a one-byte 'op' field";
  r.data_length = u32(header.data() + header_length);
  r.data_offset = offset + 8 + header_length;
  if (r.op != kChunk && r.data_length > size_ - r.data_offset) {
    return "the file ends at byte " + str(size_) + " inside this record (its data claims " +
           str(r.data_length) + " bytes): truncated, or a damaged length";
  }
  return "";
}

std::unique_ptr<std::uint8_t[]> BagFile::readData(std::uint64_t offset, std::size_t n,
                                                  std::string& error) {
  std::unique_ptr<std::uint8_t[]> data = allocateBytes(n);
  if (!data) {
    error = "cannot allocate " + str(n) + " bytes to read";
  } else if (!readAt(offset, data.get(), n)) {
    error = std::string("read error: ") + std::strerror(errno);
    data.reset();
  }
  return data;
}

}  // namespace drivetrain_stiffness::bag
