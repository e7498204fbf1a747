/* See twin_a.c. */
__attribute__((noinline)) static int twin(int x)
{
    volatile char buf[256];
    buf[0] = (char)x;
    return buf[0];
}

int qrt_twin_b(int x)
{
    return twin(x) + 2;
}
