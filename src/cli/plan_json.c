#include "plan_json.h"

#include "end_check.h"

#include <stdlib.h>

void format_exact_number(char *buf, double x)
{
    int digits;
    for (digits = 10; digits < 17; digits++) {
        snprintf(buf, EXACT_NUMBER_LEN, "%.*g", digits, x);
        if (strtod(buf, NULL) == x)
            return;
    }
    snprintf(buf, EXACT_NUMBER_LEN, "%.17g", x);
}

static void write_number(FILE *out, double x)
{
    char buf[EXACT_NUMBER_LEN];
    format_exact_number(buf, x);
    fputs(buf, out);
}

static void write_joints(FILE *out, const double q[3])
{
    int i;
    for (i = 0; i < 3; i++) {
        fputs(i ? ", " : "[", out);
        write_number(out, q[i]);
    }
    fputc(']', out);
}

/* The IK branch an xyz start or goal took, as "key": {...}; nothing for a
 * joints target (its branch is {ANY, ANY}). */
static void write_ik(FILE *out, const char *key,
                     const struct qrt_ik_branch *branch)
{
    if (branch->facing == QRT_FACING_ANY && branch->elbow == QRT_ELBOW_ANY)
        return;
    fprintf(out, "  \"%s\": {\"facing\": \"%s\", \"elbow\": \"%s\"},\n", key,
            qrt_ik_facing_name(branch->facing),
            qrt_ik_elbow_name(branch->elbow));
}

void plan_write_json(FILE *out, const struct qrt_plan *plan,
                     const struct stage_times *t)
{
    int ok = plan->status == QRT_STATUS_OK, i;
    fprintf(out, "{\n  \"version\": 1,\n  \"status\": \"%s\",\n",
            qrt_plan_status_name(plan->status));
    if (plan->status == QRT_STATUS_CAPACITY && plan->points_dropped > 0)
        fprintf(out,
                "  \"detail\": \"%ld obstacle points dropped: more than "
                "the point table holds even as %.0f mm voxels; not planning "
                "on a partial cloud\",\n",
                plan->points_dropped, 1000.0 * plan->voxel_m);
    else
        fprintf(out, "  \"detail\": \"%s\",\n", plan->detail);
    if (ok) {
        fprintf(out, "  \"waypoints_deg\": [");
        for (i = 0; i < plan->n_waypoints; i++) {
            fprintf(out, "%s\n    ", i ? "," : "");
            write_joints(out, plan->waypoints_deg[i]);
        }
        fprintf(out, "\n  ],\n  \"cost_deg\": %.6f,\n", plan->cost_deg);
        /* null: no point in reach, nothing to be clear of */
        if (plan->clearance_m >= QRT_CLEARANCE_NONE_M)
            fprintf(out, "  \"clearance_m\": null,\n");
        else { /* exactly: a bound rounded up would not be one */
            fputs("  \"clearance_m\": ", out);
            write_number(out, plan->clearance_m);
            fputs(",\n", out);
        }
    }
    if (plan->status != QRT_STATUS_UNREACHABLE &&
        plan->status != QRT_STATUS_CAPACITY) {
        fprintf(out, "  \"start_deg\": ");
        write_joints(out, plan->start_deg);
        fprintf(out, ",\n");
        write_ik(out, "start_ik", &plan->start_ik);
        if (plan->status != QRT_STATUS_START_BLOCKED) {
            fprintf(out, "  \"goal_deg\": ");
            write_joints(out, plan->goal_deg);
            fprintf(out, ",\n");
            write_ik(out, "goal_ik", &plan->goal_ik);
        }
    }
    if (end_check_measured(plan))
        fprintf(out, "  \"end_clearance_m\": %.6f,\n", plan->end_clearance_m);
    fprintf(out,
            "  \"stats\": {\"points\": %ld, \"points_ignored\": %ld, "
            "\"points_dropped\": %ld, \"voxel_m\": %g, \"cells_blocked\": %ld, "
            "\"nodes_expanded\": %ld, \"sampled_nodes\": %ld, ",
            plan->points, plan->points_ignored, plan->points_dropped,
            plan->voxel_m, plan->cells_blocked, plan->nodes_expanded,
            plan->sampled_nodes);
    if (ok)
        fprintf(out, "\"lattice_cost_deg\": %.6f, ", plan->lattice_cost_deg);
    fprintf(out,
            "\"lattice_path_nodes\": %ld, \"start_node\": %ld, "
            "\"goal_node\": %ld,\n    \"time_us\": {\"convert\": %ld, "
            "\"search\": %ld, \"certify\": %ld, \"total\": %ld}}\n}\n",
            plan->lattice_path_nodes, plan->start_node, plan->goal_node,
            t->convert_us, t->search_us, t->certify_us, t->total_us);
}

void mask_write_json(FILE *out, const struct qrt_mask *mask)
{
    const struct qrt_lattice *lat = &mask->lat;
    long n = qrt_lattice_node_count(lat), i, written = 0;
    fprintf(out, "{\"version\": 1, \"grid_deg\": ");
    write_number(out, lat->grid_deg);
    fprintf(out, ", \"n\": [%d, %d, %d], \"lo_deg\": ", lat->n[0], lat->n[1],
            lat->n[2]);
    write_joints(out, lat->lo_deg);
    fprintf(out,
            ", \"alpha_wraps\": %s, \"cells_blocked\": %ld,\n "
            "\"blocked\": [",
            lat->alpha_wraps ? "true" : "false", qrt_mask_count_blocked(mask));
    for (i = 0; i < n; i++)
        if (qrt_mask_blocked_index(mask, i))
            fprintf(out, "%s%ld",
                    written++ % 16 ? ", " : (written > 1 ? ",\n  " : ""), i);
    fprintf(out, "]}\n");
}
