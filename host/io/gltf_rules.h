// The Khronos glTF validator's rules that matter to uvpress, checked on load.
//
// uvpress reads an asset's meshes (positions, indices, UVs, normals, tangents) and carries
// everything else through unchanged, so an input's own errors reach the output. The full
// validator is a Node program (tools/validate-gltf.mjs); a user's run cannot depend on it,
// so this is a port of the subset that concerns buffers, accessors and mesh data, with the
// validator's codes and its way of counting (one issue per reference where it counts per
// reference), so that a count here is the count the validator prints for the same codes:
//
//   buffers      BUFFER_VIEW_TOO_LONG                      per bufferView
//   accessors    ACCESSOR_OFFSET_ALIGNMENT, ACCESSOR_TOTAL_OFFSET_ALIGNMENT,
//                ACCESSOR_TOO_LONG                         per accessor
//   byteStride   ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE per sampler input/output,
//                SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE          per skin,
//                MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE per primitive,
//                MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE per further attribute accessor
//                                                           sharing a view without a stride
//   primitives   MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT      per primitive,
//                ACCESSOR_INDEX_OOB, ACCESSOR_INDEX_PRIMITIVE_RESTART
//                                                           per index value and primitive
//   values       ACCESSOR_INVALID_FLOAT                     per non-finite component,
//                ACCESSOR_MIN_MISMATCH, ACCESSOR_MAX_MISMATCH,
//                ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND, ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND
//                                                           per component of an accessor's min/max,
//                ACCESSOR_VECTOR3_NON_UNIT (NORMAL, TANGENT xyz; | |v| - 1 | > 0.00674),
//                ACCESSOR_INVALID_SIGN (TANGENT w not +-1)  per element and primitive
//
// Values are compared as the validator does: float components in single precision
// (declared bounds rounded to float), integer ones as stored (normalized or not), a NaN
// making its component's actual bounds NaN. Value checks skip sparse accessors, matrices
// of 1- or 2-byte components (column padding) and accessors that do not fit their view
// (that is reported once, as ACCESSOR_TOO_LONG). Every read is bounds-checked: a malformed
// asset gives issues, never a crash.
#pragma once

#include "io/gltf_io.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace uvpress::io {

struct RuleIssue {
  std::string code;     // the validator's code, e.g. "ACCESSOR_INDEX_OOB"
  std::string pointer;  // JSON pointer of the object, e.g. "/meshes/0/primitives/0/indices"
  std::string message;
};

// Every issue of the subset above in `file` (all of them errors in the validator).
std::vector<RuleIssue> check_rules(const GltfFile& file);

// The codes check_rules reports, as listed above.
const std::vector<std::string>& rule_codes();

// Issues per code, in code order.
std::map<std::string, size_t> count_by_code(const std::vector<RuleIssue>& issues);

// What reports carry as `input_validation`: {"errors": n, "codes": {code: n}}.
nlohmann::ordered_json validation_json(const std::vector<RuleIssue>& issues);

// "127 glTF validation errors (126 ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE, 1 ...)":
// the count, then the codes by count (most first), at most `codes` of them.
std::string describe_issues(const std::vector<RuleIssue>& issues, size_t codes = 3);

}  // namespace uvpress::io
