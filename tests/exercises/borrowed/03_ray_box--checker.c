/* Borrowed from the checker: the driver's own answer for the case.
 * expect: uses ex_driver_this, a part of the checker
 */
#include <stddef.h>
#include "sidx/sidx.h"

struct ex_driver;
extern const struct ex_driver ex_driver_this;

int ray_box(const sidx_ray *r, const sidx_aabb *box, float tmin, float tmax, float *t_near, float *t_far)
{
    const void *volatile driver = &ex_driver_this; /* the driver: its reference is one field away */
    (void)r, (void)box, (void)tmin, (void)tmax, (void)t_near, (void)t_far;
    return driver != NULL;
}
