/* A small strict JSON reader (RFC 8259) for scene files: whole document
 * in, a tree out, or one error message with the byte offset. */
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
    size_t count;       /* items of an array or object */
    double number;      /* JSON_NUMBER; also 0/1 for JSON_BOOL */
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

/* Member of an object, or NULL. */
const struct json *json_get(const struct json *obj, const char *key);
const char *json_type_name(enum json_type t);

#endif
