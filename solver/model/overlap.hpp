// Bodies that intersect at the start are an input error (issue 11): contact can only push
// surfaces apart that have not crossed, so an overlap would be resolved by an explosion or
// not at all. Bodies may touch (a vertex on another body's surface), not intersect.
#pragma once

namespace qdemsph {

struct Model;

// Throws InputError naming the two bodies, a surface point (vertex or triangle centroid) of
// one that lies inside a tet of the other (beyond round-off), its position and the depth, for
// the first such pair found.
// Pairs of fixed bodies are not checked (they never touch each other).
// Cost: O(surface vertices + tets) of each pair of bodies whose bounding boxes overlap.
void check_initial_overlap(const Model& model);

}  // namespace qdemsph
