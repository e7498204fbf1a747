/* A small strict JSON reader (RFC 8259) for scene files: whole document
 * in, a tree out, or one error message with the byte offset. A tree costs
 * about 50 bytes a value; one member of the root may be left unbuilt
 * (json_parse_deferring) and read an item at a time (json_each_item). Its
 * allocations count against the command line's budget (budget.h). */
#ifndef QRT_CLI_JSON_H
#define QRT_CLI_JSON_H

#include <stddef.h>

enum json_type {
    JSON_NULL,
    JSON_BOOL,
    JSON_NUMBER,
    JSON_STRING,
    JSON_ARRAY,
    JSON_OBJECT
};

struct json {
    enum json_type type;
    int deferred;       /* an array checked but not built: items is NULL */
    size_t count;       /* items of an array or object */
    double number;      /* JSON_NUMBER; also 0/1 for JSON_BOOL; for a
                           deferred array, the byte offset of its '[' */
    char *string;       /* JSON_STRING (NUL-terminated, no NUL inside) */
    struct json *items; /* JSON_ARRAY and JSON_OBJECT values */
    char **keys;        /* JSON_OBJECT keys, parallel to items */
};

/* Nesting deeper than this is refused (a scene needs 4). */
#define JSON_MAX_DEPTH 32

/* Parse text[0..len). Returns a tree to free with json_free, or NULL with
 * a message in err ("at byte N: ..."). Numbers that overflow a double are
 * refused. */
struct json *json_parse(const char *text, size_t len, char *err,
                        size_t err_len);
void json_free(struct json *j);

/* As json_parse, but the value of the root object's member named defer,
 * if it is an array, is only checked (each item parsed, then freed), and
 * its node is a deferred JSON_ARRAY: count items, no tree. */
struct json *json_parse_deferring(const char *text, size_t len,
                                  const char *defer, char *err, size_t err_len);

/* Call fn with each item of array (deferred or not; for a deferred one,
 * text and len must be what it was parsed from), in order, each item's
 * tree freed after its call. Returns 0, or -1 when fn returns non-zero or
 * an item cannot be built (then with a message in err). */
int json_each_item(const char *text, size_t len, const struct json *array,
                   int (*fn)(void *ctx, size_t i, const struct json *item),
                   void *ctx, char *err, size_t err_len);

/* Member of an object, or NULL. */
const struct json *json_get(const struct json *obj, const char *key);
const char *json_type_name(enum json_type t);

#endif
