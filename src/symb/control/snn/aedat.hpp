// AEDAT 2.0 files: the jAER / cAER format for recorded address events, so spike rasters of a run
// can be analysed offline with the neuromorphic community's tools (jAER, aedat Python readers).
//
// Layout: ASCII header lines each starting with '#' and ending with "\r\n", the first exactly
// "#!AER-DAT2.0"; then 8-byte records, big-endian: 32-bit address, 32-bit timestamp in us.
// The header ends at the first byte that is not '#' at the start of a line; so (in jAER too) a
// first record whose address starts with byte 0x23 (module 35) would be taken for a header line:
// writers that use module bits should not start a file with module 35.
//
// The control layer opens no files: the writer appends to a byte string the caller writes out
// (symb run writes spikes.aedat to the run's output folder), the reader parses bytes the caller
// read.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "symb/control/snn/aer.hpp"
#include "symb/kernel/result.hpp"

namespace symb::control::snn {

struct AedatFile {
  // The header lines without '#', the one space after it and the line end; the version line
  // excluded.
  std::vector<std::string> header;
  std::vector<AerEvent> events;
};

// The header: "#!AER-DAT2.0\r\n", then one "# <line>\r\n" per comment line (a line holding '\r'
// or '\n' is cut there). Append records with append_aedat_records().
std::string aedat_header(std::span<const std::string> comments);
void append_aedat_records(std::string& out, std::span<const AerEvent> events);

// Parses a whole file. Errors are located: "LINE:COLUMN: message" in the header (a missing or
// different version line, a header line without its "\r\n" end); "byte OFFSET: message" in the
// records (a trailing partial record). A file with a header and no records is valid.
kernel::Result<AedatFile> read_aedat(std::string_view bytes);

}  // namespace symb::control::snn
