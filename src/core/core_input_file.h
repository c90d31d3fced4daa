// The one reader of user-supplied input files (scenarios, sweeps, goldens,
// scenes, CSV logs).
//
// An input file must be a regular file (a FIFO, device, folder or socket is
// refused before it is read, so /dev/zero cannot fill memory and a FIFO cannot
// block), no larger than the cap of its kind, and UTF-8 text. Every refusal is an
// InputError naming the file as the caller describes it ("scenario 'a.yaml'",
// "a.yaml:3: scene 'b.xml'") and, for text, the line and column of the first
// byte that is not UTF-8.
#pragma once

#include <cstddef>
#include <string>

namespace vlab {

/// Cap of YAML files (scenario, sweep, golden.yaml): 1 MiB, 100 times the
/// largest shipped one (cases/cubes/stage3.yaml, 10 KB).
constexpr std::size_t kMaxYamlBytes = std::size_t{1} << 20;
/// Cap of MJCF scene files and the files they include: 4 MiB, 200 times the
/// largest shipped one (mjcf/hoap3/hoap3.xml, 18 KB).
constexpr std::size_t kMaxSceneBytes = std::size_t{4} << 20;
/// Cap of CSV logs read back (vlab compare, golden logs, plots): 1 GiB.
constexpr std::size_t kMaxCsvBytes = std::size_t{1} << 30;
/// Cap of JSON files read back (a run's summary.json): 64 MiB.
constexpr std::size_t kMaxJsonBytes = std::size_t{64} << 20;

/// Reads `path` whole after checking that it is a regular file of at most
/// `max_bytes`, and that its bytes are UTF-8. `what` names the file in messages
/// ("scenario 'a.yaml'"); a bad byte is reported as "PATH:LINE:COLUMN".
/// Throws InputError on any of these faults, and on a read error.
std::string ReadInputFile(const std::string& path, const std::string& what, std::size_t max_bytes);

/// The checks of ReadInputFile that need no reading (exists, is a regular file,
/// at most `max_bytes`), for a file another library then opens (MuJoCo's scene).
void CheckInputFile(const std::string& path, const std::string& what, std::size_t max_bytes);

/// The byte offset of the first byte of `text` that is not part of a valid
/// UTF-8 sequence (overlong forms, surrogates and code points past U+10FFFF are
/// invalid), or std::string::npos when all of it is UTF-8.
std::size_t FirstNonUtf8(const std::string& text);

/// Throws InputError "WHERE:LINE:COLUMN: byte 0xNN is not UTF-8 ..." at the
/// first bad byte of `text`; `where` names its source (a file, or a flag).
void CheckUtf8(const std::string& where, const std::string& text);

}  // namespace vlab
