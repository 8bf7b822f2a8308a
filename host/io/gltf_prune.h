// Pruning what a stage's replacement left behind. reparam replaces UV accessors (new ones
// are appended: the old ones may be shared) and image bytes (an image kept in a bufferView
// gets new bytes elsewhere): the old accessors, their bufferViews and the old image bytes
// would stay in the file, unreferenced, and a reparam of a reparam would grow by them.
//
// An object is removed when nothing references it in `file` any more but something did in
// `input` (or it is new since `input`): objects the input itself left unused are kept,
// they are not ours to drop. Accessors and bufferViews are pruned (reparam never leaves an
// image, texture or sampler unreferenced: it re-encodes images in place), the buffers are
// compacted over the bytes of the removed bufferViews and over the bytes that only removed
// accessors read inside a bufferView that stays (Fox keeps TEXCOORD_0 and JOINTS_0 in one
// view), and every reference is renumbered.
#pragma once

#include "io/gltf_io.h"

#include <string>

namespace uvpress::io {

struct PruneResult {
  size_t accessors = 0, buffer_views = 0;  // removed
  size_t buffer_bytes = 0;                 // removed from the buffers (whole views and parts of shared ones)
  // Why nothing was pruned, when an extension the file uses may reference accessors or
  // bufferViews in ways this pass does not know (renumbering would break it). "" otherwise.
  std::string skipped;
};

// `input`: the model as loaded, before the stage changed `file` (indices below its counts
// name the same objects in both; the stage only appended). Images whose bytes in
// file.image_bytes no longer equal their bufferView's are detached from it first (save_gltf
// then stores the new bytes).
PruneResult prune_replaced(GltfFile& file, const tinygltf::Model& input);

}  // namespace uvpress::io
