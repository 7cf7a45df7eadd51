// Text placed in HTML or SVG (an element's text, a quoted attribute's value): report.html's title and
// heading, curve.svg's labels.
#pragma once

#include <string>
#include <string_view>

namespace endorecon::eval {

// `text` with &, <, > and " written as character references.
std::string EscapeMarkup(std::string_view text);

}  // namespace endorecon::eval
