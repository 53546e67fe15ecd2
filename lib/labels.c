/* labels.c — names on a built structure's nodes (sidx/accel.h, "node
 * labels"): what a slide calls a node ("A", "L4"), shown by the lessons,
 * sidx-step, sidx-dot and sidx-view next to the node's id.
 *
 * A short array of (node, text) sorted by node, held by the structure and
 * allocated with its allocator when the first label is set.  A slide labels a handful of nodes, so a
 * sorted array with binary search is enough; a drawing that asks for
 * every node of a big tree pays one search per node.  No walk reads it. */
#include "sidx_internal.h"

typedef struct node_label {
    uint32_t node;
    char text[SIDX_LABEL_MAX];
} node_label;

/* Allocated on the first label, so that a structure without labels
 * carries one NULL pointer and nothing else. */
struct sidx__labels {
    node_label *e;
    size_t n, cap;
};

/* Index of the first label with node >= `node`. */
static size_t lower_bound(const struct sidx__labels *L, uint32_t node)
{
    size_t lo = 0, hi = L->n;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (L->e[mid].node < node) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

sidx_status sidx_accel_set_node_label(sidx_accel *a, uint32_t node, const char *label, sidx_error *err)
{
    if (!a) return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: structure is NULL");
    /* The node count from the structure's own statistics, through its
     * vtable: labels sit beside the structure and call nothing of accel.c,
     * which calls them (sidx__labels_free) when it destroys the structure. */
    sidx_accel_stats st;
    memset(&st, 0, sizeof st);
    a->vt->stats(a, &st);
    if (node >= st.nodes)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: %s has no node %u (%u nodes)",
                          a->name, node, st.nodes);
    const size_t len = label ? strlen(label) : 0;
    if (len >= SIDX_LABEL_MAX)
        return sidx__fail(err, SIDX_ERR_INVALID_ARG, "sidx_accel_set_node_label: label of %zu bytes (at most %d)",
                          len, SIDX_LABEL_MAX - 1);
    if (!a->labels && len == 0) return SIDX_OK;
    if (!a->labels) {
        a->labels = sidx__calloc(a, 1, sizeof *a->labels);
        if (!a->labels) return sidx__fail(err, SIDX_ERR_NOMEM, "sidx_accel_set_node_label: out of memory");
    }
    struct sidx__labels *L = a->labels;
    const size_t i = lower_bound(L, node);
    const int present = i < L->n && L->e[i].node == node;
    if (len == 0) { /* remove */
        if (present) {
            memmove(&L->e[i], &L->e[i + 1], (L->n - i - 1) * sizeof *L->e);
            L->n--;
        }
        return SIDX_OK;
    }
    if (!present) {
        void *p = L->e;
        if (!sidx__grow(a, &p, &L->cap, L->n + 1, sizeof *L->e))
            return sidx__fail(err, SIDX_ERR_NOMEM, "sidx_accel_set_node_label: out of memory");
        L->e = p;
        memmove(&L->e[i + 1], &L->e[i], (L->n - i) * sizeof *L->e);
        L->n++;
        L->e[i].node = node;
    }
    memcpy(L->e[i].text, label, len + 1);
    return SIDX_OK;
}

const char *sidx_accel_node_label(const sidx_accel *a, uint32_t node)
{
    if (!a || !a->labels) return NULL;
    const struct sidx__labels *L = a->labels;
    const size_t i = lower_bound(L, node);
    return i < L->n && L->e[i].node == node ? L->e[i].text : NULL;
}

void sidx__labels_free(sidx_accel *a)
{
    if (!a->labels) return;
    sidx__free(a, a->labels->e);
    sidx__free(a, a->labels);
    a->labels = NULL;
}
