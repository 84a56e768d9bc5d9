#include <iostream>
int main() { std::cout << "rigbake\n"; }
