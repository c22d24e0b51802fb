// check_structure (builder/mh_hierarchy): the one-pass heights used when children follow their parents
// (build_mh's and merge_mmh's numbering) and the depth-first search used otherwise must agree: a tree
// within the level count passes, one path too long fails, a cycle fails.
#include <gtest/gtest.h>

#include "builder/mh_hierarchy.hpp"

namespace shadowtiles {
namespace {

// Root -> one child with children -> one leaf: a path of two levels below the root. `forward`: the
// top block is block 0 and its child block is block 1 (children after parents); otherwise reversed.
MhHierarchy two_level_chain(unsigned levels, bool forward) {
  MhHierarchy h;
  h.levels = levels;
  h.size = uint32_t(1) << levels;
  h.root = {0.25f, 0.75f};
  h.root_mask = 0b10;  // child 0: empty node with children
  const uint32_t top = forward ? 0 : 1, leaf = forward ? 1 : 0;
  h.block_mask = {0, 0};
  h.block_first_child = {0, 0};
  h.block_first_value = {0, 0};
  h.block_mask[top] = 0b10, h.block_first_child[top] = 0, h.block_first_value[top] = 0;
  h.block_mask[leaf] = 0b01, h.block_first_child[leaf] = 1, h.block_first_value[leaf] = 0;
  h.child_block = {leaf};
  h.intervals = {{0.5f, 0.5f}};
  h.root_block = top;
  return h;
}

TEST(MhHierarchyStructure, BothNumberingsAcceptATreeWithinTheLevels) {
  EXPECT_TRUE(check_structure(two_level_chain(2, true)).ok());
  EXPECT_TRUE(check_structure(two_level_chain(2, false)).ok());
  EXPECT_TRUE(check_structure(two_level_chain(5, true)).ok());
}

TEST(MhHierarchyStructure, BothNumberingsRejectAPathLongerThanTheLevels) {
  EXPECT_FALSE(check_structure(two_level_chain(1, true)).ok());
  EXPECT_FALSE(check_structure(two_level_chain(1, false)).ok());
}

TEST(MhHierarchyStructure, RejectsACycle) {
  MhHierarchy h = two_level_chain(2, true);
  h.block_mask[1] = 0b10;  // the leaf block now has children: itself
  h.block_first_value[1] = 1;
  h.child_block.push_back(1);
  EXPECT_FALSE(check_structure(h).ok());
}

}  // namespace
}  // namespace shadowtiles
