// The Khronos glTF validator's rules that matter to uvpress, checked on load: a port of the
// validator's subset on buffers, accessors and mesh data (tools/validate-gltf.mjs runs the
// full one), with its codes (rule_codes()) and its way of counting, so that a count here is
// the count the validator prints for the same codes. Every read is bounds-checked: a
// malformed asset gives issues, never a crash. Why a port, which codes are counted per what,
// and how values are compared: the top of gltf_rules.cpp.
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

// Every issue of the subset in `file` (all of them errors in the validator).
std::vector<RuleIssue> check_rules(const GltfFile& file);

// The codes check_rules reports (listed, with what each counts, at the top of gltf_rules.cpp).
const std::vector<std::string>& rule_codes();

// Issues per code, in code order.
std::map<std::string, size_t> count_by_code(const std::vector<RuleIssue>& issues);

// What reports carry as `input_validation`: {"errors": n, "codes": {code: n}}.
nlohmann::ordered_json validation_json(const std::vector<RuleIssue>& issues);

// "127 glTF validation errors (126 ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE, 1 ...)":
// the count, then the codes by count (most first), at most `codes` of them.
std::string describe_issues(const std::vector<RuleIssue>& issues, size_t codes = 3);

}  // namespace uvpress::io
