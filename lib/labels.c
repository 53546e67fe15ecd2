/* labels.c — names on a built structure's nodes (sidx/accel.h, "node
 * labels"): what a slide calls a node ("A", "L4"), shown by the lessons,
 * sidx-step, sidx-dot and sidx-view next to the node's id.
 *
 * A short array of (node, text) sorted by node, held by the structure and
 * allocated with its allocator.  A slide labels a handful of nodes, so a
 * sorted array with binary search is enough; a drawing that asks for
 * every node of a big tree pays one search per node.  No walk reads it. */
#include "sidx_internal.h"

struct sidx__label {
    uint32_t node;
    char text[SIDX_LABEL_MAX];
};

/* Index of the first label with node >= `node`. */
static size_t lower_bound(const sidx_accel *a, uint32_t node)
{
    size_t lo = 0, hi = a->num_labels;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (a->labels[mid].node < node) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

sidx_status sidx_accel_set_node_label(sidx_accel *a, uint32_t node, const char *label, sidx_error *err)
{
    if (!a) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: structure is NULL");
    sidx_accel_stats st;
    memset(&st, 0, sizeof st);
    sidx_accel_stats_get(a, &st);
    if (node >= st.nodes)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: %s has no node %u (%u nodes)",
                          a->name, node, st.nodes);
    const size_t len = label ? strlen(label) : 0;
    if (len >= SIDX_LABEL_MAX)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: label of %zu bytes (at most %d)",
                          len, SIDX_LABEL_MAX - 1);
    const size_t i = lower_bound(a, node);
    const int present = i < a->num_labels && a->labels[i].node == node;
    if (len == 0) { /* remove */
        if (present) {
            memmove(&a->labels[i], &a->labels[i + 1], (a->num_labels - i - 1) * sizeof *a->labels);
            a->num_labels--;
        }
        return SIDX_OK;
    }
    if (!present) {
        void *p = a->labels;
        if (!sidx__grow(a, &p, &a->cap_labels, a->num_labels + 1, sizeof *a->labels))
            return sidx__fail(err, SIDX_ERR_NOMEM, "sidx_accel_set_node_label: out of memory");
        a->labels = p;
        memmove(&a->labels[i + 1], &a->labels[i], (a->num_labels - i) * sizeof *a->labels);
        a->num_labels++;
        a->labels[i].node = node;
    }
    memcpy(a->labels[i].text, label, len + 1);
    return SIDX_OK;
}

const char *sidx_accel_node_label(const sidx_accel *a, uint32_t node)
{
    if (!a || a->num_labels == 0) return NULL;
    const size_t i = lower_bound(a, node);
    return i < a->num_labels && a->labels[i].node == node ? a->labels[i].text : NULL;
}

void sidx__labels_free(sidx_accel *a)
{
    sidx__free(a, a->labels);
    a->labels = NULL;
    a->num_labels = a->cap_labels = 0;
}
