// A structural check of ASCII Gmsh files (MSH 2.x and 4.x) before libgmsh reads them.
// libgmsh 4.8 crashes (SIGSEGV) on some truncated files, e.g. an $Elements section that
// declares more elements than it holds, instead of reporting an error; this check turns
// such files into an InputError naming the section, the counts and the line. Binary files
// and other formats pass through unchecked (libgmsh reports those itself).
#pragma once

#include <filesystem>

namespace qdemsph {

// Throws InputError when a $Nodes or $Elements section is incomplete or malformed.
void precheck_ascii_msh(const std::filesystem::path& path);

}  // namespace qdemsph
