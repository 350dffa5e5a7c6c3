#include <cstdio>
int main() { std::puts("pteryla: skeleton"); return 0; }
