#!/bin/sh
# run_lessons.sh — run every built lesson and check its key figures.
#
#   BUILD=build sh tests/run_lessons.sh        (make test does this; BUILD=build/san under SAN=1)
#
# For each program in $BUILD/lessons/: `--help` must exit 0 and name the
# build knobs (those the lesson takes, or that it refuses them), an
# unknown option and a bad knob (--bins 1) must exit 2, a scene that
# cannot be loaded must exit 1 with a line on stderr naming the lesson
# (lessons/lesson.h does all of this),
# and a run with no arguments must exit 0 and print every "CHECK
# name=value" line listed for it below, and no CHECK line that is not
# listed: a lesson without expectations here fails, and so does a check
# a lesson prints that nothing compares (docs/adding-a-lesson.md).
# The lessons compute those values from what they measure (leak counts,
# cost comparisons, ...), so a check fails when the property stops
# holding, not when the wording changes.  A lesson whose structures are
# not registered in lib/accel_registry.def is reported as skipped.
# Then the output excerpts of docs/tutorial.md are compared with these
# runs (docs/make_tutorial.sh refreshes a copy from the saved outputs): an
# excerpt that no longer reads as its lesson prints fails.  Decimal
# numbers, ratios (3.3x) and every number on a line that gives a time (ns,
# us, ms, "% of the time") are left out of the comparison, since timings and what is
# computed from them change from run to run; text and whole numbers
# (counts) must match.
# Run from the repository root.  Exit status 1 if anything failed.

BUILD=${BUILD:-build}
DIR=$BUILD/lessons
DEF=lib/accel_registry.def

# The structures a lesson needs (all must be registered).
needs() {
    case $1 in
    03_*|05_*) echo "bvh bvh-sweep bvh-everyb bvh-median bvh-middle" ;;
    04_*) echo "bvh bvh-sweep bvh-everyb bvh-median bvh-middle bvh-sbvh" ;;
    06_*) echo "bvh kdtree grid octree" ;;
    07_*|21_*) echo "grid grid-nomailbox" ;;
    08_*) echo "grid grid2 grid-irregular kdtree" ;;
    09_*|22_*) echo "kdtree kdtree-median kdtree-middle" ;;
    10_*|11_*|25_*) echo "kdtree" ;;
    12_*) echo "octree quadtree bsp" ;;
    13_*) echo "bvh kdtree grid octree" ;;
    14_*) echo "bvh bvh4 bvh8" ;;
    15_*) echo "bvh rayclass" ;;
    16_*) echo "bvh" ;;
    17_*) echo "bvh bvh-obb" ;;
    18_*|19_*) echo "bvh" ;;
    20_*) echo "bvh kdtree grid" ;;
    23_*) echo "grid grid-irregular" ;;
    24_*|26_*) echo "bvh" ;;
    27_*) echo "kdtree" ;;
    *) echo "" ;;
    esac
}

# The CHECK lines a lesson must print.
expect() {
    case $1 in
    01_ray_triangle) echo "worked_example_agrees=1 d_zero_all_miss=1 negative_t_rejected=1 edge_vertex_hit=1
                           watertight_leaks=0 moller_leaks_more=1 mesh_watertight_leaks_le_moller=1" ;;
    02_bounding_volumes) echo "conservative=1 area_predicts_hit_rate=1 kdop_within_aabb=1 obb_tighter_on_rod=1
                               sphere_fits_round_object=1" ;;
    03_bvh_partitioning) echo "candidate_costs_reproduced=1 slide_candidates_match=1 sah_cost_lower=1 sah_tree_cost_lower=1
                               sah_fewer_tests_per_ray=1" ;;
    04_bvh_build_review) echo "same_hits=1 reindexed_contiguous=1 sweep_cost_lowest=1 binned_fewer_root_candidates=1
                               spatial_same_hits=1 spatial_sah_lower=1 spatial_fewer_entered=1 spatial_duplicates=1" ;;
    05_bvh_traversal) echo "same_hit=1 ordered_visits_fewer=1 ordered_fewer_on_average=1" ;;
    06_object_vs_space) echo "same_hits=1 bvh_boxes_overlap=1 kd_cells_disjoint=1 kd_stops_at_first_hit=1
                              review_same_hits=1 review_bvh_refs_once=1 review_spatial_duplicates=1
                              review_grid_tests_more_than_trees=1" ;;
    07_uniform_grid) echo "resolution_formula=1 dda_cells_in_order=1 dda_state_gives_library_cells=1 mailbox_saves_tests=1
                         middle_lambda_best=1" ;;
    08_teapot_in_stadium) echo "teapot_floor_stands_seen=1 grid_map_varies=1 same_hits=1 uniform_grid_worst=1 adaptive_beats_uniform=1 irregular_adapts=1" ;;
    09_kdtree_build) echo "same_hits=1 sah_cost_lower=1 sah_thin_leaves=1 cost_curve_min_is_split=1" ;;
    10_kdtree_traversal) echo "same_hit=1 stack_trace_consistent=1 cannot_terminate_seen=1 split_cases_shown=1" ;;
    11_kd_node_layout) echo "decoded_matches=1 children_side_by_side=1" ;;
    12_octree_bsp) echo "same_hits=1 kd_deck_constants_fewer_tris_than_octree=1 kd_default_c_trav_fatter_leaves=1
                         bsp_planes_cut_the_board=1 painter_order_back_to_front=1" ;;
    13_worst_case) echo "worst_cases_linear=1" ;;
    # No time is checked: speed-ups cannot be promised on a shared or
    # single-core CI machine; the checks are on hits and counted work.
    14_going_faster) echo "same_hits=1 wide_fewer_node_visits=1 frustum_box_tests_le_plain=1
                           frustum_4x4_same_walk=1 frustum_8x8_saves_box_tests=1 frustum_culls_nodes=1
                           saved_box_tests_come_from_culls=1" ;;
    15_shadows) echo "same_answers=1 any_hit_cheaper=1 light_buffer_saves=1" ;;
    16_time_vs_error) echo "watertight_leaks=0 moller_leaks_more=1 robust_box_misses=0 plain_box_misses_more=1" ;;
    17_oriented_bvh) echo "same_hits=1 obb_fewer_box_tests=1 obb_fewer_box_hits=1 obb_more_memory=1" ;;
    18_beams_and_cones) echo "tree_matches_brute=1 conservative=1 tile_beam_fewer_visits=1
                              candidates_exceed_hits=1 subdivision_narrows=1 own_subdivision_matches=1
                              cones_cost_more=1" ;;
    19_instancing) echo "hits_agree=1 nested_hits_agree=1 one_shared_child=1 instancing_saves_memory=1" ;;
    20_log_n) echo "tree_work_exponent_small=1 grid_exponent_near_third=1" ;;
    21_mailboxes) echo "same_hits=1 replay_matches_library=1 mailbox_saves_tests=1 per_object_saves_most=1
                        sharing_loses_skips=1 sharing_moves_lines=1" ;;
    22_kd_round_robin) echo "same_hits=1 round_robin_scale_invariant=1 largest_extent_cheaper=1
                             gap_grows_when_stretched=1" ;;
    23_irregular_grid) echo "base_within_finest_level=1 merged_cells_are_boxes=1 expanded_over_subsets=1
                             finest_level_12_steps=1 irregular_fewer_steps=1 same_hit=1 same_hits=1
                             fewer_cells_visited=1 needs_more_memory=1" ;;
    24_spawning_rays) echo "spawn_self_intersections=0 spawn_missed_occluders=0 hack_hits_itself_far_away=1
                            hack_misses_when_small=1" ;;
    25_kd_slide_example) echo "slide_tree=1 rows_match_slide=1 cannot_terminate_rows=2 ends_in_L3=1 same_hit=1
                               cheap_step_deeper=1" ;;
    26_bvh_optimise) echo "sah_lower=1 events_sum_to_gain=1 same_hits=1" ;;
    27_building_kdtrees_quickly) echo "top_sifts_everything=1 root_exceeds_cache=1 most_nodes_fit_cache=1
                                       image_builds_part=1 hits_agree=1 expand_event_then_subtree=1
                                       whole_tree_is_eager=1 city_builds_few=1 city_hits_identical=1" ;;
    *) echo "" ;;
    esac
}

# A build knob the lesson takes, and the lines of its output (counts, not
# times) that the knob must change: a knob that is parsed but never reaches
# the build would leave them as they are.
knob_args() {
    case $1 in
    03_*) echo "--bins 8" ;;
    04_*) echo "--bins 8" ;;
    05_*) echo "--leaf-size 1" ;;
    06_*) echo "--leaf-size 1" ;;
    07_*) echo "--lambda 0.25" ;;
    08_*) echo "--lambda 0.25" ;;
    09_*) echo "--c-trav 4" ;;
    12_*) echo "--leaf-size 1" ;;
    13_*) echo "--leaf-size 1" ;;
    14_*) echo "--leaf-size 1" ;;
    15_*) echo "--leaf-size 1" ;;
    17_*) echo "--leaf-size 1" ;;
    18_*) echo "--leaf-size 1" ;;
    19_*) echo "--leaf-size 1" ;;
    20_*) echo "--max-depth 4" ;;
    21_*) echo "--lambda 1" ;;
    22_*) echo "--leaf-size 8" ;;
    23_*) echo "--lambda 0.5" ;;
    25_*) echo "--max-depth 1" ;;
    27_*) echo "--leaf-size 8" ;;
    *) echo "" ;;
    esac
}
knob_lines() {
    case $1 in
    03_*) grep -c 'candidate axis' ;;                          # the SAH candidates printed
    04_*) grep '^  bvh  ' | awk '{print $(NF-7), $(NF-6)}' ;;  # SAH candidates: all, at the root
    05_*) grep '^  ordered ' | awk '{print $2, $3, $4}' ;;     # visits, box and triangle tests per ray
    06_*) grep 'sibling pairs' ;;                               # BVH and kd-tree node pairs
    07_*) grep 'One ray through' ;;
    08_*) grep 'The middle pixel through' ;;                    # the uniform grid's resolution
    09_*) grep -m1 'candidate axis' ;;
    12_*) grep 'leaves per depth' ;;
    13_*) grep -m1 ' speck ' ;;                                 # BVH triangle tests per ray
    14_*) grep '^  bvh ' | awk '{print $4, $5, $6}' ;;         # nodes, boxes, triangles per ray
    15_*) grep 'BVH closest hit' | awk '{print $4, $5}' ;;     # triangle tests, boxes per query
    17_*) grep ' bvh  ' | awk '{print $(NF-4), $(NF-3), $(NF-2)}' ;;
    18_*) grep 'tests more' ;;                                  # the bundle tree's box tests
    19_*) grep '^  instanced ' | head -1 | awk '{print $2}' ;;  # the object BVH's memory
    20_*) grep '^  icosphere:2 ' ;;
    21_*) grep -m1 'lambda = ' ;;
    22_*) grep 'round-robin, middle ' ;;
    23_*) grep '^  grid-irregular ' | awk '{print $2, $3, $4}' ;;
    25_*) grep "SAH, a cheap step" ;;
    27_*) grep '^  eager ' | awk '{print $4, $5}' ;;            # the eager kd-tree's nodes and references
    esac
}

# An output with what varies from run to run left out: times (and every
# number on a line giving one), ratios and decimals; text and counts stay.
norm() {
    awk '{ if ($0 ~ /[0-9.]+ ?(ns|us|ms)([^A-Za-z]|$)|% of the time/) gsub(/[0-9]+(\.[0-9]+)?/, "#")
           gsub(/[0-9]+(\.[0-9]+)?x/, "#x"); gsub(/[0-9]*\.[0-9]+/, "#"); gsub(/[ \t]+/, " "); print }' "$1"
}

registered() { grep -q "^SIDX_ACCEL(\"$1\"" "$DEF" 2>/dev/null; }

# Under the sanitizers each lesson runs once, without the second run of its
# build knob: whether a knob reaches the build is the same answer in every
# build (make test asks it), and a second run under ASan only doubles the time.
# The same holds for the four runs with bad arguments (lessons/lesson.h
# answers them for every lesson): under the sanitizers the first lesson
# alone takes them.
case $BUILD in
*/san | */tsan) KNOB_RUNS=0 ARG_RUNS=first ;;
*) KNOB_RUNS=1 ARG_RUNS=all ;;
esac

if [ ! -d "$DIR" ]; then
    echo "run_lessons: no lessons built in $DIR"
    exit 1
fi

passed=0 failed=0 skipped=0
out=${TMPDIR:-/tmp}/sidx_lesson.$$
outs=${TMPDIR:-/tmp}/sidx_lesson_outs.$$
mkdir -p "$outs" || exit 1
trap 'rm -f "$out"; rm -rf "$outs"' EXIT INT TERM

for prog in "$DIR"/*; do
    [ -f "$prog" ] && [ -x "$prog" ] || continue
    name=$(basename "$prog")
    missing=""
    for s in $(needs "$name"); do
        registered "$s" || missing="$missing $s"
    done
    if [ -n "$missing" ]; then
        echo "SKIP $name (not registered:$missing)"
        skipped=$((skipped + 1))
        continue
    fi
    why=""
    if [ "$ARG_RUNS" = all ] || [ $((passed + failed)) -eq 0 ]; then
        "$prog" --help >"$out" 2>&1 || why="$why --help did not exit 0;"
        grep -q "build knobs" "$out" || why="$why --help does not name the build knobs;"
        "$prog" --bins 1 >/dev/null 2>&1
        [ $? -eq 2 ] || why="$why a bad build knob (--bins 1) did not exit 2;"
        "$prog" --no-such-option >/dev/null 2>&1
        [ $? -eq 2 ] || why="$why a bad option did not exit 2;"
        "$prog" /no/such/scene.obj >/dev/null 2>"$out"
        rc=$?
        [ $rc -eq 1 ] && grep -q "^$name: " "$out" || why="$why a missing scene file did not exit 1 with a message;"
    fi
    start=$(date +%s)
    "$prog" >"$outs/$name.out" 2>"$outs/$name.err"
    rc=$?
    cat "$outs/$name.out" "$outs/$name.err" >"$out"
    secs=$(( $(date +%s) - start ))
    [ $rc -eq 0 ] || why="$why exit code $rc;"
    for want in $(expect "$name"); do
        grep -qx "CHECK $want" "$out" || {
            got=$(grep "^CHECK ${want%%=*}=" "$out" | head -1)
            why="$why expected CHECK $want, got '${got:-nothing}';"
        }
    done
    knob=$(knob_args "$name")
    if [ -n "$knob" ] && [ "$KNOB_RUNS" = 1 ]; then
        before=$(knob_lines "$name" <"$out")
        # shellcheck disable=SC2086  # the knob and its value are two words
        after=$("$prog" $knob 2>&1 | knob_lines "$name")
        if [ -z "$before" ] || [ "$before" = "$after" ]; then
            why="$why the build knob $knob did not change its output;"
        fi
    fi
    # The review table's verdicts (deck 001's marks) come from counts: a
    # second run reads the same, times aside.
    case $name in
    06_*) "$prog" 2>/dev/null | norm - >"$outs/again.norm"
          norm "$outs/$name.out" | cmp -s - "$outs/again.norm" ||
              why="$why a second run prints other text or counts: $(norm "$outs/$name.out" | diff - "$outs/again.norm" | grep '^[<>]' | head -2 | tr '\n' ' ');" ;;
    esac
    # The decks give the SAH's constants no values: lesson 25 prints the ratios it uses as its
    # own, and attributes none to a deck.
    case $name in
    25_*) grep -q "SAH, a cheap step, C_trav : C_tri = 1 : 1.5 " "$out" || why="$why the cheap step's ratio is not printed;"
          if grep -Eq "deck'?s? [0-9.]+ ?: ?[0-9.]+" "$out"; then
              why="$why a ratio attributed to a deck: $(grep -Em1 "deck'?s? [0-9.]+ ?: ?[0-9.]+" "$out");"
          fi ;;
    esac
    if [ -z "$(expect "$name")" ]; then
        why="$why no expectations: list its CHECK lines in expect() of tests/run_lessons.sh;"
    else
        for got in $(sed -n 's/^CHECK \([^=]*\)=.*/\1/p' "$out"); do
            case " $(expect "$name" | tr '\n' ' ') " in
            *" $got="*) ;;
            *) why="$why CHECK $got is printed but not expected (add it to expect() of tests/run_lessons.sh);" ;;
            esac
        done
    fi
    if [ -z "$why" ]; then
        echo "PASS $name (${secs}s)"
        passed=$((passed + 1))
    else
        echo "FAIL $name (${secs}s):$why"
        tail -5 "$out" | sed 's/^/     | /'
        failed=$((failed + 1))
    fi
done

# sidx-tour: the heading of the build events says how many it prints (40, or
# every one with --full), never a count of -1.
tour=$BUILD/bin/sidx-tour
if [ -x "$tour" ] && registered kdtree; then
    tourdir=${TMPDIR:-/tmp}/sidx_tour.$$
    why=""
    "$tour" --accel kdtree --scene kd-slide --full --out "$tourdir" >"$out" 2>&1 || why="$why --full exit code $?;"
    grep -q -- "-- build (every decision)" "$out" || why="$why --full does not say it prints every decision;"
    grep -q "first -" "$out" && why="$why --full prints a negative count: $(grep -m1 'first -' "$out");"
    "$tour" --accel kdtree --scene kd-slide --out "$tourdir" >"$out" 2>&1 || why="$why exit code $?;"
    grep -q -- "-- build (first 40 decisions)" "$out" || why="$why without --full it does not say 'first 40 decisions';"
    rm -rf "$tourdir"
    if [ -z "$why" ]; then
        echo "PASS sidx-tour"
        passed=$((passed + 1))
    else
        echo "FAIL sidx-tour:$why"
        failed=$((failed + 1))
    fi
fi

# the tutorial's excerpts against the runs above (only when every lesson ran:
# make_tutorial.sh would run the missing ones itself)
doc=docs/tutorial.md
if [ -f "$doc" ] && [ $skipped -eq 0 ] && [ $((passed + failed)) -gt 1 ]; then
    cp "$doc" "$outs/tutorial.md"
    if LESSON_OUTPUTS=$outs sh docs/make_tutorial.sh "$BUILD" "$outs/tutorial.md" >"$out" 2>&1; then
        norm "$doc" >"$outs/doc.norm"
        norm "$outs/tutorial.md" >"$outs/run.norm"
        if diff "$outs/doc.norm" "$outs/run.norm" >"$out"; then
            echo "PASS $doc excerpts"
            passed=$((passed + 1))
        else
            echo "FAIL $doc excerpts: they differ from the lessons' output (refresh with make docs):"
            head -20 "$out" | sed 's/^/     | /'
            failed=$((failed + 1))
        fi
    else
        echo "FAIL $doc excerpts: docs/make_tutorial.sh fails:"
        tail -5 "$out" | sed 's/^/     | /'
        failed=$((failed + 1))
    fi
fi

echo "lessons: $passed passed, $failed failed, $skipped skipped"
[ $failed -eq 0 ]
