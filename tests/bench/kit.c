/* kit.c — the shared test kit (tests/common/testkit.c) compiled into sidx-bench,
 * so the bench and the suites use the same ray sets, files and reference. */
#include "../common/testkit.c"
