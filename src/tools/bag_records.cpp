#include "bag_records.hpp"  // NOLINT(build/include_subdir)

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
  return forEachField(p, n, [&](std::string_view name, std::string_view value) { fields[std::string(name)] = value; });
}

std::string parseChunkRecord(const std::uint8_t* p, std::size_t n, ChunkRecord& r, bool& cut_off) {
  cut_off = true;
  if (n < 4) return "record cut off inside its header length (" + str(n) + " of 4 bytes)";
  const std::uint32_t header_length = u32(p);
  if (n - 4 < header_length + std::size_t{4}) {
    return "record header of " + str(header_length) + " bytes runs past the chunk's end (" + str(n - 4) +
           " bytes left)";
  }
  r.data_length = u32(p + 4 + header_length);
  const std::size_t data_begin = 8 + std::size_t{header_length};
  if (r.data_length > n - data_begin) {
    return "record data of " + str(r.data_length) + " bytes runs past the chunk's end (" + str(n - data_begin) +
           " bytes left)";
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

std::string decompressChunk(const std::string& compression, const std::uint8_t* in, std::size_t in_size,
                            std::uint8_t* out, std::uint32_t size) {
  if (compression != "lz4" && compression != "bz2") return "chunk compression '" + compression + "' unknown";
  if (in_size > 0xffffffffu) return "compressed chunk of " + str(in_size) + " bytes (more than 4 GiB)";
  unsigned int written = size;
  auto* source = const_cast<char*>(reinterpret_cast<const char*>(in));
  auto* dest = reinterpret_cast<char*>(out);
  const bool lz4 = compression == "lz4";
  const auto n = static_cast<unsigned int>(in_size);
  const int rc = lz4 ? roslz4_buffToBuffDecompress(source, n, dest, &written)
                     : BZ2_bzBuffToBuffDecompress(dest, &written, source, n, 0, 0);
  if (rc != (lz4 ? ROSLZ4_OK : BZ_OK)) {
    return "this " + compression + " chunk does not decompress (" + (lz4 ? "roslz4" : "libbz2") + " code " +
           std::to_string(rc) + ")";
  }
  if (written != size) {
    return "this " + compression + " chunk decompresses to " + str(written) + " bytes, its header says " + str(size);
  }
  return "";
}

std::uint64_t maxUncompressedSize(const std::string& compression, std::uint64_t compressed) {
  constexpr std::uint64_t kMiB = 1u << 20;
  return compression == "bz2" ? 255 * compressed + kMiB : 255 * compressed + 64;
}

std::unique_ptr<std::uint8_t[]> allocateBytes(std::size_t n) {
  return std::unique_ptr<std::uint8_t[]>(new (std::nothrow) std::uint8_t[n > 0 ? n : 1]);
}

BagFile::BagFile(const std::string& path) {
  file_.reset(std::fopen(path.c_str(), "rb"));
  if (!file_) throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  if (fseeko(file_.get(), 0, SEEK_END) != 0) throw InvalidInput("'" + path + "': cannot be read: " + std::strerror(errno));
  size_ = static_cast<std::uint64_t>(ftello(file_.get()));
}

bool BagFile::readAt(std::uint64_t offset, void* out, std::size_t n) {
  return fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) == 0 && std::fread(out, 1, n, file_.get()) == n;
}

std::string BagFile::readRecord(std::uint64_t offset, TopRecord& r) {
  r.offset = offset;
  const std::uint64_t left = size_ - offset;
  std::uint8_t length[4];
  if (left < 4) return "truncated: the file ends at byte " + str(size_) + " inside a record's header length";
  if (!readAt(offset, length, 4)) return std::string("read error: ") + std::strerror(errno);
  const std::uint32_t header_length = u32(length);
  if (left - 4 < header_length + std::uint64_t{4}) {
    return "the file ends at byte " + str(size_) + " inside this record (its header claims " + str(header_length) +
           " bytes): truncated, or a damaged length";
  }
  std::vector<std::uint8_t> header(header_length + std::size_t{4});
  if (!readAt(offset + 4, header.data(), header.size())) return std::string("read error: ") + std::strerror(errno);
  r.fields.clear();
  const std::string error = parseFields(header.data(), header_length, r.fields);
  if (!error.empty()) return "damaged record: " + error;
  if (!fixedField(r.fields, "op", r.op)) return "damaged record: header without a one-byte 'op' field";
  r.data_length = u32(header.data() + header_length);
  r.data_offset = offset + 8 + header_length;
  if (r.op != kChunk && r.data_length > size_ - r.data_offset) {
    return "the file ends at byte " + str(size_) + " inside this record (its data claims " + str(r.data_length) +
           " bytes): truncated, or a damaged length";
  }
  return "";
}

std::unique_ptr<std::uint8_t[]> BagFile::readData(std::uint64_t offset, std::size_t n, std::string& error) {
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
