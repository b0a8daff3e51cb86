#pragma once
// The text of the shipped IDL files (idl/*.idl), embedded at build time (cmake/EmbedIdl.cmake),
// so that a recording carries, as each type's schema, the IDL its payloads were written with.
#include <span>
#include <string_view>

namespace teleop::idl {

struct IdlFile {
  std::string_view name;  ///< file name, e.g. "Teleop.idl"
  std::string_view text;  ///< its text, byte for byte
};

/// Every IDL file the program was built with.
std::span<const IdlFile> idl_files();

/// The text of the IDL file that defines `type_name` (a fully qualified DDS type name such as
/// "teleop::SlaveState": a `struct SlaveState` inside `module teleop`); empty if none does.
std::string_view idl_text_for_type(std::string_view type_name);

}  // namespace teleop::idl
