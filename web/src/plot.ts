// A live plot of the force magnitude on the tool (N) over the last few seconds.
export class ForcePlot {
  private readonly values: number[] = [];
  peak = 0;

  constructor(private readonly canvas: HTMLCanvasElement, private readonly capacity = 300) {}

  push(f: number): void {
    this.values.push(f);
    if (this.values.length > this.capacity) this.values.shift();
    this.peak = Math.max(this.peak, f);
  }

  /** Largest force currently shown, N. */
  shownMax(): number {
    return this.values.reduce((a, b) => Math.max(a, b), 0);
  }

  draw(): void {
    const ctx = this.canvas.getContext('2d');
    if (!ctx) return;
    const { width: w, height: h } = this.canvas;
    ctx.clearRect(0, 0, w, h);
    const top = Math.max(0.05, this.shownMax() * 1.2);
    ctx.strokeStyle = '#555';
    ctx.beginPath(); ctx.moveTo(0, h - 1); ctx.lineTo(w, h - 1); ctx.stroke();
    ctx.strokeStyle = '#ffb347';
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    this.values.forEach((v, i) => {
      const x = (i / (this.capacity - 1)) * w, y = h - 2 - (v / top) * (h - 16);
      if (i === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
    });
    ctx.stroke();
    ctx.fillStyle = '#ccc';
    ctx.font = '11px sans-serif';
    ctx.fillText(`${(this.values[this.values.length - 1] ?? 0).toFixed(3)} N (scale ${top.toFixed(2)} N)`, w - 150, 12);
  }
}
