#pragma once
// A folder name is a name from the experiment file that becomes a folder
// of the run: a camera's frames are stored under frames/<camera name>/. It
// is checked when the file is read, so a name no file system takes is
// refused naming its key and line before any run is created, instead of
// failing with the system's "File name too long" once logging starts. The
// rule is the POSIX portable file name characters without the dot (letters,
// digits, - and _: no path separator, no hidden or relative names, the same
// on every file system and in a URL of the live page), and at most
// kMaxFolderNameBytes bytes, far below any NAME_MAX (255) so that the
// suffixes bosfuse adds stay valid too.

#include <cstddef>
#include <string>
#include <string_view>

namespace bosfuse::acquisition {

inline constexpr std::size_t kMaxFolderNameBytes = 64;

// Empty when `name` may be a folder name; otherwise what is wrong with it.
std::string folder_name_problem(std::string_view name);

}  // namespace bosfuse::acquisition
