// The version of every JSON report uvpress writes (`--report`, batch's NAME.report.json and
// summary.json): the first key, "schema". Raised when a key is renamed, removed or changes
// meaning, so that a pipeline reading reports can refuse one it does not know; new keys
// keep it.
#pragma once

namespace uvpress {

constexpr int kReportSchema = 1;

}  // namespace uvpress
