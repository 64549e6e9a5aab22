// Galileo E1 OS primary codes (Galileo OS SIS ICD Issue 2.1, Annex C), PRN 1-50 in order: each
// 1023 hexadecimal digits (4092 chips), the first chip the most significant bit of the first digit.
#pragma once

namespace skytrace::baseband::detail {

extern const char* const kGalileoE1bPrimaryHex[50];  // E1-B (data component)
extern const char* const kGalileoE1cPrimaryHex[50];  // E1-C (pilot component)

}  // namespace skytrace::baseband::detail
