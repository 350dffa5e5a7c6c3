#pragma once
// Generic ImGui editors for JSON values: every scene section (moult settings, controls, a tract object,
// packing options) can be inspected and edited even where no dedicated widget exists, so the viewer
// keeps up with section formats the modules extend. The scene reader validates what is written.
#include <string>

#include "pteryla/core/json.hpp"

namespace pteryla::viewer {

// Tree of widgets for `j` (objects, arrays, numbers, booleans, strings, [x,y,z] triples). Keys and
// elements can be added and removed. Returns true when `j` changed this frame.
bool jsonEditor(const char* id, Json& j);

// The value as editable JSON text with an Apply button. `buffer` keeps the text between frames (it is
// refilled from `j` when empty or when `j` changed elsewhere); returns true when Apply parsed a new value
// into `j`; a parse error is shown under the text.
struct JsonTextState {
  std::string buffer, error, shown;
};
bool jsonTextEditor(const char* id, Json& j, JsonTextState& state, float height = 160.0f);

}  // namespace pteryla::viewer
